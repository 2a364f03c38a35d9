#![no_main]
// Binary Gmsh 2.2 and 4.1 (seeds written by Gmsh and meshio).
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let _ = atlasmesh::formats::parse_fe_mesh_raw(&atlasmesh_fuzz::name("msh"), data);
});
