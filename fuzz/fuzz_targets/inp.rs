#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let p = atlasmesh_fuzz::file(data, "inp");
    if let Ok(deck) = atlasmesh::formats::read_inp(&p) {
        let _ = deck.with_nodes(&deck.mesh.nodes);
    }
    let _ = atlasmesh::formats::read_fe_mesh_raw(&p);
});
