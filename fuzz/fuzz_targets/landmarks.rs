#![no_main]
// Scalismo JSON and .pts landmark files.
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    for ext in ["json", "pts"] {
        let name = atlasmesh_fuzz::name(ext);
        let _ = atlasmesh::formats::landmarks::parse_landmarks::<2>(&name, text);
        let _ = atlasmesh::formats::landmarks::parse_landmarks::<3>(&name, text);
    }
});
