#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    // A material recipe's text parsed and resolved (calibration fitted, law checked), then
    // the law evaluated over the HU of a CT.
    if let Ok(text) = std::str::from_utf8(data)
        && let Ok(recipe) =
            atlasmesh::materials::MaterialRecipe::parse(&atlasmesh_fuzz::name("toml"), text)
        && let Ok(r) = recipe.law()
    {
        let table = atlasmesh::materials::ModulusTable::new(&r, [-1024.0, 3071.0]);
        for hu in [-1024.0, -100.0, 0.0, 250.0, 1000.0, 3071.0] {
            let _ = (r.modulus(hu), table.at(hu));
        }
    }
});
