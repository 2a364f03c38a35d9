#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let _ = atlasmesh::formats::parse_fe_mesh_raw(&atlasmesh_fuzz::name("msh"), data);
});
