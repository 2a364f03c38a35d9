#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let name = atlasmesh_fuzz::name("inp");
    if let Ok(text) = std::str::from_utf8(data)
        && let Ok(deck) = atlasmesh::formats::parse_inp(&name, text)
    {
        let _ = deck.with_nodes(&deck.mesh.nodes);
    }
    let _ = atlasmesh::formats::parse_fe_mesh_raw(&name, data);
});
