#![no_main]
// The sets config (TOML), read and evaluated on a small hexahedral block.
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(c) = atlasmesh::mesh::SetsConfig::parse(&atlasmesh_fuzz::name("toml"), text) {
        let _ = c.evaluate(&atlasmesh_fuzz::block(), &[[0.0, 0.0, 0.0]]);
    }
});
