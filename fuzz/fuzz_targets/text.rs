#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let p = atlasmesh_fuzz::file(data, "txt");
    let _ = atlasmesh::formats::read_outlines(&p, true);
});
