#![no_main]
// Long CSV populations (`shape,point,x,y`) and landmark CSVs.
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let name = atlasmesh_fuzz::name("csv");
    let _ = atlasmesh::formats::parse_outlines(&name, data, false);
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = atlasmesh::formats::landmarks::parse_landmarks_csv::<2>(&name, text);
        let _ = atlasmesh::formats::landmarks::parse_landmarks_csv::<3>(&name, text);
    }
});
