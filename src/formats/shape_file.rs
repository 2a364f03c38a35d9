//! Shapes out: a fitted outline or surface in the formats asked ([`ShapeFormat`]), each
//! readable by atlasmesh and by the field's programs (VTK/ParaView, meshio, trimesh, 3D
//! Slicer).

use super::atomic::write_atomic;
use super::helpers::xyz;
use crate::error::{Error, Result};
use crate::geometry::Shape;
use std::fmt::Write as _;
use std::path::Path;

/// A format for shapes (outlines and surfaces).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ShapeFormat {
    /// VTK XML PolyData (`.vtp`): lines (2D) or triangles (3D).
    Vtp,
    /// Legacy VTK 4.2, ASCII (`.vtk`): an UNSTRUCTURED_GRID of lines or triangles, which
    /// VTK, ParaView, meshio and atlasmesh read.
    Vtk,
    /// Binary PLY (`.ply`, 3D).
    Ply,
    /// Binary STL (`.stl`, 3D, single precision).
    Stl,
}

impl ShapeFormat {
    /// The file extension.
    pub fn extension(self) -> &'static str {
        match self {
            ShapeFormat::Vtp => "vtp",
            ShapeFormat::Vtk => "vtk",
            ShapeFormat::Ply => "ply",
            ShapeFormat::Stl => "stl",
        }
    }
    /// The format named `s` (`vtp`, `vtk`, `ply`, `stl`).
    pub fn parse(s: &str) -> Option<Self> {
        [Self::Vtp, Self::Vtk, Self::Ply, Self::Stl]
            .into_iter()
            .find(|f| f.extension().eq_ignore_ascii_case(s.trim()))
    }
    /// Whether shapes of dimension `d` can be written so (PLY and STL hold surfaces).
    pub fn holds(self, d: usize) -> bool {
        d == 3 || matches!(self, ShapeFormat::Vtp | ShapeFormat::Vtk)
    }
}

/// Writes `shape` to `path` in `format`.
///
/// # Errors
/// [`Error::Parameter`] for an outline in PLY or STL; I/O errors.
pub fn write_shape<const D: usize>(
    path: &Path,
    shape: &Shape<D>,
    format: ShapeFormat,
) -> Result<()> {
    if !format.holds(D) {
        return Err(Error::Parameter(format!(
            "{}: {} holds surfaces; write 2D outlines as vtp or vtk",
            path.display(),
            format.extension()
        )));
    }
    match format {
        ShapeFormat::Vtp => super::write_vtp(path, shape),
        ShapeFormat::Vtk => write_atomic(path, vtk_polydata(shape).as_bytes()),
        ShapeFormat::Ply | ShapeFormat::Stl => {
            let s = Shape::<3> {
                name: shape.name.clone(),
                points: shape.points.iter().map(xyz).collect(),
                facets: shape
                    .facets
                    .iter()
                    .map(|f| std::array::from_fn(|k| f[k.min(D - 1)]))
                    .collect(),
                landmarks: Vec::new(),
            };
            if format == ShapeFormat::Ply {
                super::write_ply(path, &s)
            } else {
                super::write_stl(path, &s)
            }
        }
    }
}

/// Legacy VTK 4.2 ASCII of a shape: its facets as line (2D) or triangle (3D) cells of an
/// UNSTRUCTURED_GRID (meshio reads no POLYDATA).
fn vtk_polydata<const D: usize>(shape: &Shape<D>) -> String {
    let mut s = format!(
        "# vtk DataFile Version 4.2\natlasmesh {}\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS {} double\n",
        env!("CARGO_PKG_VERSION"),
        shape.points.len()
    );
    for p in &shape.points {
        let q = xyz(p);
        let _ = writeln!(s, "{:.17e} {:.17e} {:.17e}", q[0], q[1], q[2]);
    }
    let n = shape.facets.len();
    let _ = writeln!(s, "CELLS {n} {}", n * (D + 1));
    for f in &shape.facets {
        let _ = write!(s, "{D}");
        for i in f {
            let _ = write!(s, " {i}");
        }
        s.push('\n');
    }
    let _ = writeln!(s, "CELL_TYPES {n}");
    let t = if D == 2 { "3\n" } else { "5\n" };
    s.push_str(&t.repeat(n));
    s
}
