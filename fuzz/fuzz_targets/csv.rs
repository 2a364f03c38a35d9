#![no_main]
// Long CSV populations (`shape,point,x,y`) and landmark CSVs.
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let p = atlasmesh_fuzz::file(data, "csv");
    let _ = atlasmesh::formats::read_outlines(&p, false);
    let _ = atlasmesh::formats::landmarks::read_landmarks_csv::<2>(&p);
    let _ = atlasmesh::formats::landmarks::read_landmarks_csv::<3>(&p);
});
