#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let _ = atlasmesh::formats::read_surface(&atlasmesh_fuzz::file(data, "ply"));
});
