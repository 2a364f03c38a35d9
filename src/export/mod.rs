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

/// One set as a 0/1 mask array named `set_NAME`.
fn set_mask_xml(s: &mut String, name: &str, members: &[usize], n: usize) {
    let mut mask = vec![0u8; n];
    for &m in members {
        if m < n {
            mask[m] = 1;
        }
    }
    let _ = writeln!(
        s,
        "        <DataArray type=\"UInt8\" Name=\"set_{name}\" format=\"ascii\">"
    );
    for chunk in mask.chunks(32) {
        s.push_str("          ");
        for v in chunk {
            s.push(if *v == 1 { '1' } else { '0' });
            s.push(' ');
        }
        s.push('\n');
    }
    s.push_str("        </DataArray>\n");
}

/// Writes an FE mesh as VTU (readable by ParaView and meshio), with cell data `jacobian_min`
/// and `scaled_jacobian_min` (corner minima, section 5.3), and, when `reference` is given (the
/// same mesh before morphing), point data `displacement` (node position minus reference).
/// Node sets and element sets are point and cell data `set_NAME` (1 for members, else 0);
/// surfaces are not written (VTU has no face sets; use `.inp`, `.msh` or `.feb`).
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
    let mut s = String::with_capacity(mesh.nodes.len() * 80 + ne * 60);
    s.push_str("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n  <UnstructuredGrid>\n");
    let _ = writeln!(
        s,
        "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">",
        mesh.nodes.len(),
        ne
    );
    s.push_str("      <PointData>\n");
    for (name, members) in &mesh.sets.node_sets {
        set_mask_xml(&mut s, name, members, mesh.nodes.len());
    }
    if let Some(r) = reference {
        s.push_str("        <DataArray type=\"Float64\" Name=\"displacement\" NumberOfComponents=\"3\" format=\"ascii\">\n");
        for (p, o) in mesh.nodes.iter().zip(&r.nodes) {
            let z = if D > 2 { p[2] - o[2] } else { 0.0 };
            let _ = writeln!(
                s,
                "          {:.17e} {:.17e} {:.17e}",
                p[0] - o[0],
                p[1] - o[1],
                z
            );
        }
        s.push_str("        </DataArray>\n");
    }
    s.push_str("      </PointData>\n");
    s.push_str("      <CellData Scalars=\"scaled_jacobian_min\">\n");
    for (name, members) in &mesh.sets.element_sets {
        set_mask_xml(&mut s, name, members, ne);
    }
    s.push_str("        <DataArray type=\"Float64\" Name=\"jacobian_min\" format=\"ascii\">\n");
    for e in q {
        let _ = writeln!(s, "          {:.17e}", e.jacobian_min);
    }
    s.push_str("        </DataArray>\n        <DataArray type=\"Float64\" Name=\"scaled_jacobian_min\" format=\"ascii\">\n");
    for e in q {
        let _ = writeln!(s, "          {:.17e}", e.scaled_jacobian_min);
    }
    s.push_str("        </DataArray>\n      </CellData>\n");
    points_xml(&mut s, &mesh.nodes);
    s.push_str("      <Cells>\n        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
    for e in 0..ne {
        s.push_str("          ");
        for n in mesh.element(e) {
            let _ = write!(s, "{n} ");
        }
        s.push('\n');
    }
    s.push_str("        </DataArray>\n        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    for e in 0..ne {
        let _ = writeln!(s, "          {}", (e + 1) * k);
    }
    s.push_str("        </DataArray>\n        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n");
    for _ in 0..ne {
        let _ = writeln!(s, "          {}", mesh.kind.vtk_type());
    }
    s.push_str(
        "        </DataArray>\n      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n",
    );
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
