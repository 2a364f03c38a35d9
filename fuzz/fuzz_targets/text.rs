#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let _ = atlasmesh::formats::parse_outlines(&atlasmesh_fuzz::name("txt"), data, true);
});
