#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    // The header-only dimension reader reads a file; the loader parses the bytes.
    let p = atlasmesh_fuzz::file(data, "safetensors");
    let _ = atlasmesh::formats::atlas_dimension(&p);
    let name = atlasmesh_fuzz::name("safetensors");
    let _ = atlasmesh::model::Atlas::<2>::from_bytes(&name, data);
    let _ = atlasmesh::model::Atlas::<3>::from_bytes(&name, data);
});
