#![no_main]
// Legacy VTK: surfaces (POLYGONS), outlines (LINES) and FE meshes (UNSTRUCTURED_GRID).
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let p = atlasmesh_fuzz::file(data, "vtk");
    let _ = atlasmesh::formats::read_surface(&p);
    let _ = atlasmesh::formats::read_outlines(&p, true);
    let _ = atlasmesh::formats::read_fe_mesh_raw(&p);
});
