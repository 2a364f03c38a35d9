#![no_main]
// Legacy VTK: surfaces (POLYGONS), outlines (LINES) and FE meshes (UNSTRUCTURED_GRID).
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let name = atlasmesh_fuzz::name("vtk");
    let _ = atlasmesh::formats::parse_surface(&name, data);
    let _ = atlasmesh::formats::parse_outlines(&name, data, true);
    let _ = atlasmesh::formats::parse_fe_mesh_raw(&name, data);
});
