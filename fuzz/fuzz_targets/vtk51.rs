#![no_main]
// Legacy VTK 5.1 (OFFSETS/CONNECTIVITY, METADATA), ASCII and binary, polydata and
// unstructured grids with mixed cells (seeds written by PyVista and meshio).
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let name = atlasmesh_fuzz::name("vtk");
    let _ = atlasmesh::formats::parse_surface(&name, data);
    let _ = atlasmesh::formats::parse_outlines(&name, data, true);
    let _ = atlasmesh::formats::parse_fe_mesh_raw(&name, data);
});
