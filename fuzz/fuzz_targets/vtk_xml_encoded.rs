#![no_main]
// VTK XML as VTK writes it: appended raw and base64 data, UInt32/UInt64 headers, big-endian,
// zlib and LZ4 blocks (seeds written by PyVista and VTK), read as a surface, an outline and
// a mesh.
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let _ = atlasmesh::formats::parse_surface(&atlasmesh_fuzz::name("vtp"), data);
    let _ = atlasmesh::formats::parse_outlines(&atlasmesh_fuzz::name("vtp"), data, true);
    let _ = atlasmesh::formats::parse_fe_mesh_raw(&atlasmesh_fuzz::name("vtu"), data);
});
