//! Writing results: VTU (VTK XML unstructured grid) for FE meshes, VTP (VTK XML polydata) for
//! shapes, and the solver formats in [`solver`] (Abaqus/CalculiX `.inp`, Gmsh `.msh` 4.1,
//! FEBio `.feb` 4.0, legacy VTK). Files are written atomically (temporary name, then rename).

pub mod solver;

pub use solver::{MeshFormat, write_mesh};

use crate::error::Result;
use crate::fe::FeMesh;
use crate::fe::quality::mesh_quality;
use crate::geometry::{Point, Shape};
use std::fmt::Write as _;
use std::path::Path;

fn points_xml<const D: usize>(out: &mut String, pts: &[Point<D>]) {
    out.push_str("      <Points>\n        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n");
    for p in pts {
        let z = if D > 2 { p[2] } else { 0.0 };
        let _ = writeln!(out, "          {:.17e} {:.17e} {:.17e}", p[0], p[1], z);
    }
    out.push_str("        </DataArray>\n      </Points>\n");
}

/// One `DataArray` in VTK's inline binary encoding: base64 of a UInt64 byte count followed by
/// the little-endian values (`header_type="UInt64"`, no compression).
fn binary_array(
    s: &mut String,
    vtk_type: &str,
    name: Option<&str>,
    components: usize,
    bytes: &[u8],
) {
    use base64::Engine as _;
    let mut raw = Vec::with_capacity(8 + bytes.len());
    raw.extend_from_slice(&(bytes.len() as u64).to_le_bytes());
    raw.extend_from_slice(bytes);
    let name = name.map(|n| format!(" Name=\"{n}\"")).unwrap_or_default();
    let comps = if components > 1 {
        format!(" NumberOfComponents=\"{components}\"")
    } else {
        String::new()
    };
    let _ = writeln!(
        s,
        "        <DataArray type=\"{vtk_type}\"{name}{comps} format=\"binary\">\n          {}\n        </DataArray>",
        base64::engine::general_purpose::STANDARD.encode(&raw)
    );
}

fn f64_bytes(v: impl IntoIterator<Item = f64>) -> Vec<u8> {
    v.into_iter().flat_map(|x| x.to_le_bytes()).collect()
}

fn i64_bytes(v: impl IntoIterator<Item = usize>) -> Vec<u8> {
    v.into_iter()
        .flat_map(|x| (x as i64).to_le_bytes())
        .collect()
}

/// One set as a 0/1 mask array named `set_NAME`.
fn set_mask(s: &mut String, name: &str, members: &[usize], n: usize) {
    let mut mask = vec![0u8; n];
    for &m in members {
        if m < n {
            mask[m] = 1;
        }
    }
    binary_array(s, "UInt8", Some(&format!("set_{name}")), 1, &mask);
}

/// Writes an FE mesh as VTU (VTK XML, binary arrays; readable by ParaView and meshio), with
/// cell data `jacobian_min` and `scaled_jacobian_min` (corner minima, section 5.3), and, when
/// `reference` is given (the same mesh before morphing), point data `displacement` (node
/// position minus reference). Node sets and element sets are point and cell data `set_NAME`
/// (1 for members, else 0); surfaces are not written (VTU has no face sets; use `.inp`,
/// `.msh` or `.feb`).
pub fn write_vtu<const D: usize>(
    path: &Path,
    mesh: &FeMesh<D>,
    reference: Option<&FeMesh<D>>,
) -> Result<()> {
    write_vtu_with_quality(path, mesh, reference, &mesh_quality(mesh))
}

/// [`write_vtu`] with the corner Jacobians already at hand (one per element).
pub fn write_vtu_with_quality<const D: usize>(
    path: &Path,
    mesh: &FeMesh<D>,
    reference: Option<&FeMesh<D>>,
    q: &[crate::fe::quality::ElementQuality],
) -> Result<()> {
    let k = mesh.kind.nodes();
    let ne = mesh.num_elements();
    let z = |p: &Point<D>| if D > 2 { p[2] } else { 0.0 };
    let mut s = String::with_capacity(mesh.nodes.len() * 40 + ne * 100);
    s.push_str("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n  <UnstructuredGrid>\n");
    let _ = writeln!(
        s,
        "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">",
        mesh.nodes.len(),
        ne
    );
    s.push_str("      <PointData>\n");
    for (name, members) in &mesh.sets.node_sets {
        set_mask(&mut s, name, members, mesh.nodes.len());
    }
    if let Some(r) = reference {
        let d = mesh
            .nodes
            .iter()
            .zip(&r.nodes)
            .flat_map(|(p, o)| [p[0] - o[0], p[1] - o[1], z(p) - z(o)]);
        binary_array(&mut s, "Float64", Some("displacement"), 3, &f64_bytes(d));
    }
    s.push_str("      </PointData>\n      <CellData Scalars=\"scaled_jacobian_min\">\n");
    for (name, members) in &mesh.sets.element_sets {
        set_mask(&mut s, name, members, ne);
    }
    if q.len() == ne {
        let j = f64_bytes(q.iter().map(|e| e.jacobian_min));
        binary_array(&mut s, "Float64", Some("jacobian_min"), 1, &j);
        let sj = f64_bytes(q.iter().map(|e| e.scaled_jacobian_min));
        binary_array(&mut s, "Float64", Some("scaled_jacobian_min"), 1, &sj);
    }
    s.push_str("      </CellData>\n      <Points>\n");
    let pts = f64_bytes(mesh.nodes.iter().flat_map(|p| [p[0], p[1], z(p)]));
    binary_array(&mut s, "Float64", None, 3, &pts);
    s.push_str("      </Points>\n      <Cells>\n");
    binary_array(
        &mut s,
        "Int64",
        Some("connectivity"),
        1,
        &i64_bytes(mesh.connectivity.iter().copied()),
    );
    binary_array(
        &mut s,
        "Int64",
        Some("offsets"),
        1,
        &i64_bytes((1..=ne).map(|e| e * k)),
    );
    binary_array(
        &mut s,
        "UInt8",
        Some("types"),
        1,
        &vec![mesh.kind.vtk_type(); ne],
    );
    s.push_str("      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n");
    crate::io::write_atomic(path, s.as_bytes())
}

/// Writes a shape as VTP: an outline as line cells, a surface as polygons.
pub fn write_vtp<const D: usize>(path: &Path, shape: &Shape<D>) -> Result<()> {
    let mut s = String::new();
    s.push_str("<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n  <PolyData>\n");
    let tag = if D == 2 { "Lines" } else { "Polys" };
    let (nl, np) = if D == 2 {
        (shape.facets.len(), 0)
    } else {
        (0, shape.facets.len())
    };
    let _ = writeln!(
        s,
        "    <Piece NumberOfPoints=\"{}\" NumberOfVerts=\"0\" NumberOfLines=\"{nl}\" NumberOfStrips=\"0\" NumberOfPolys=\"{np}\">",
        shape.points.len()
    );
    points_xml(&mut s, &shape.points);
    let _ = writeln!(
        s,
        "      <{tag}>\n        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">"
    );
    for f in &shape.facets {
        let _ = writeln!(
            s,
            "          {}",
            f.iter()
                .map(|i| i.to_string())
                .collect::<Vec<_>>()
                .join(" ")
        );
    }
    s.push_str("        </DataArray>\n        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    for i in 0..shape.facets.len() {
        let _ = writeln!(s, "          {}", (i + 1) * D);
    }
    let _ = writeln!(
        s,
        "        </DataArray>\n      </{tag}>\n    </Piece>\n  </PolyData>\n</VTKFile>"
    );
    crate::io::write_atomic(path, s.as_bytes())
}
