#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let p = atlasmesh_fuzz::file(data, "msh");
    let _ = atlasmesh::formats::read_fe_mesh_raw(&p);
});
