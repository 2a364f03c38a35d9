#![no_main]
// Scalismo JSON and .pts landmark files.
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    for ext in ["json", "pts"] {
        let p = atlasmesh_fuzz::file(data, ext);
        let _ = atlasmesh::formats::landmarks::read_landmarks::<2>(&p);
        let _ = atlasmesh::formats::landmarks::read_landmarks::<3>(&p);
    }
});
