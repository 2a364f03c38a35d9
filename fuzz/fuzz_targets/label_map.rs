#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    // Each image reader on the bytes (a detached data file is refused), then, for an image
    // that reads and is small, label 1's mask and surface, and its materials under a
    // hexahedron spanning it.
    let none = |_: &str| -> atlasmesh::Result<Vec<u8>> {
        Err(atlasmesh::Error::Parameter("no detached file".into()))
    };
    let read = [
        atlasmesh::formats::nifti::parse_nifti(&atlasmesh_fuzz::name("nii"), data),
        atlasmesh::formats::nrrd::parse_nrrd(&atlasmesh_fuzz::name("nrrd"), data, &none),
        atlasmesh::formats::metaimage::parse_metaimage(&atlasmesh_fuzz::name("mha"), data, &none),
    ];
    for file in read.into_iter().flatten() {
        let name = atlasmesh_fuzz::name("nii");
        if file.image.check(&name).is_err() || file.image.voxel_count() > 1 << 20 {
            continue;
        }
        let table = atlasmesh::image::LabelTable::default();
        if let Ok(mask) = atlasmesh::image::label_mask(&file.image, &[1], &name, &table) {
            let s = atlasmesh::image::label_surface(&file.image, &mask, "fuzz");
            let _ = atlasmesh::geometry::prepare_surface(s.shape);
        }
        // The image as a CT under one hexahedron spanning it.
        if let Ok(ct) = atlasmesh::materials::CtField::new(&file.image) {
            let mut mesh = atlasmesh::mesh::HexMesh::block(1);
            let d = file.image.dims;
            for p in &mut mesh.nodes {
                *p = file
                    .image
                    .world(std::array::from_fn(|k| p[k] * (d[k] as f64 - 1.0)));
            }
            let recipe = atlasmesh::materials::MaterialRecipe::default().law();
            if let Ok(r) = recipe {
                let _ = atlasmesh::materials::map_materials(&mesh, &ct, &r);
            }
        }
    }
});
