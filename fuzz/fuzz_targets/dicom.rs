#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    // The bytes as the one file of a DICOM folder, read as a series (its tags, rescale,
    // orientation and pixel data, decoded), then, for a series that reads and is small, as a
    // CT under one hexahedron spanning it.
    let file = atlasmesh_fuzz::file(data, "dcm");
    let Some(dir) = file.parent() else {
        return;
    };
    let Ok(read) = atlasmesh::formats::dicom_series::read_dicom_series(dir) else {
        return;
    };
    let image = read.image;
    if image.check(&file).is_err() || image.voxel_count() > 1 << 20 {
        return;
    }
    if let Ok(ct) = atlasmesh::materials::CtField::new(&image) {
        let mut mesh = atlasmesh::mesh::HexMesh::block(1);
        let d = image.dims;
        for p in &mut mesh.nodes {
            *p = image.world(std::array::from_fn(|k| p[k] * (d[k] as f64 - 1.0).max(0.0)));
        }
        if let Ok(r) = atlasmesh::materials::MaterialRecipe::default().law() {
            let _ = atlasmesh::materials::map_materials(&mesh, &ct, &r);
        }
    }
});
