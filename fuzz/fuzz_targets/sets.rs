#![no_main]
// The sets config (TOML), read and evaluated on a small hexahedral block.
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let p = atlasmesh_fuzz::file(data, "toml");
    if let Ok(c) = atlasmesh::mesh::sets::SetsConfig::read(&p) {
        let _ = c.evaluate(&atlasmesh_fuzz::block(), &[[0.0, 0.0, 0.0]]);
    }
});
