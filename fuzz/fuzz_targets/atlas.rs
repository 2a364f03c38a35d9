#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let p = atlasmesh_fuzz::file(data, "safetensors");
    let _ = atlasmesh::formats::atlas_dimension(&p);
    let _ = atlasmesh::model::Atlas::<2>::load(&p);
    let _ = atlasmesh::model::Atlas::<3>::load(&p);
});
