#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let _ = atlasmesh::formats::parse_surface(&atlasmesh_fuzz::name("vtp"), data);
});
