//! Work on FE mesh files: quality, conversion between formats (optionally to quadratic
//! elements, with sets added), and repair; for meshes of either dimension.

use super::Progress;
use crate::error::{Error, Result};
use crate::formats::{read_fe_mesh_raw, read_outlines, read_surface, to_dimension, write_mesh};
use crate::geometry::{ClosestPointIndex, Point, Shape, Similarity};
use crate::mesh::quality::{QualityDistribution, distribution, mesh_quality};
use crate::mesh::{FeMesh, RepairParams, RepairReport, SetsConfig, repair_with_quality};
use crate::model::Atlas;
use std::path::Path;

/// An FE mesh file read once, in the dimension of its elements.
#[derive(Clone, Debug)]
pub enum AnyMesh {
    /// Quadrilaterals or triangles.
    Two(FeMesh<2>),
    /// Hexahedra or tetrahedra (linear or quadratic).
    Three(FeMesh<3>),
}

/// Reads an FE mesh file (format from the extension) in the dimension of its elements.
pub fn read_any_mesh(path: &Path) -> Result<AnyMesh> {
    let m = read_fe_mesh_raw(path)?;
    Ok(if m.kind.dimension() == 2 {
        AnyMesh::Two(to_dimension(path, m)?)
    } else {
        AnyMesh::Three(to_dimension(path, m)?)
    })
}

/// Whether `path` names an atlas file (`.safetensors`).
pub fn is_atlas_file(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("safetensors"))
}

/// The element quality of the mesh in `path` (section 5.3): corner Jacobians, scaled
/// Jacobians, their percentiles, the elements below the acceptance bound, edge ratios.
pub fn mesh_file_quality(path: &Path) -> Result<QualityDistribution> {
    fn of<const D: usize>(m: &FeMesh<D>) -> QualityDistribution {
        distribution(m, &mesh_quality(m))
    }
    Ok(match read_any_mesh(path)? {
        AnyMesh::Two(m) => of(&m),
        AnyMesh::Three(m) => of(&m),
    })
}

/// Converts the mesh in `input` (or, for an atlas file, its mean mesh in the data's frame and
/// unit, [`Atlas::data_frame`], or in the reference frame for an atlas of format version 2;
/// the atlas's landmarks for the sets) to `output` (format from the extension): made
/// quadratic first with `quadratic` (hex8 to hex20, tet4 to tet10), with the sets of `sets`
/// evaluated on the (quadratic) mesh, in the reference frame, added.
pub fn convert_mesh_file(
    input: &Path,
    output: &Path,
    sets: Option<&SetsConfig>,
    quadratic: bool,
) -> Result<()> {
    fn mean_mesh<const D: usize>(
        path: &Path,
    ) -> Result<(FeMesh<D>, Vec<Point<D>>, Option<Similarity<D>>)> {
        let a = Atlas::<D>::load(path)?;
        if a.mesh.num_elements() == 0 {
            return Err(Error::Parameter(format!(
                "{}: the atlas has no mesh (built with --no-mesh): there is no mean mesh to \
                 convert; build it with a mesh, or write its mean shape with `instance`",
                path.display()
            )));
        }
        let l = a.landmarks.iter().map(|&i| a.mean[i]).collect();
        Ok((a.mesh, l, a.data_frame))
    }
    if is_atlas_file(input) {
        if crate::formats::atlas_dimension(input)? == 2 {
            let (m, l, f) = mean_mesh::<2>(input)?;
            convert(m, &l, output, sets, quadratic, f.as_ref())
        } else {
            let (m, l, f) = mean_mesh::<3>(input)?;
            convert(m, &l, output, sets, quadratic, f.as_ref())
        }
    } else {
        match read_any_mesh(input)? {
            AnyMesh::Two(m) => convert(m, &[], output, sets, quadratic, None),
            AnyMesh::Three(m) => convert(m, &[], output, sets, quadratic, None),
        }
    }
}

/// [`convert_mesh_file`] of a mesh of dimension `D` with its landmarks.
fn convert<const D: usize>(
    mut mesh: FeMesh<D>,
    landmarks: &[Point<D>],
    output: &Path,
    sets: Option<&SetsConfig>,
    quadratic: bool,
    frame: Option<&Similarity<D>>,
) -> Result<()> {
    if quadratic {
        mesh = match mesh.to_quadratic() {
            Some(q) => q,
            None if mesh.kind.linear() != mesh.kind => mesh,
            None => {
                return Err(Error::Parameter(format!(
                    "--quadratic: {} elements have no quadratic kind here (hex8 and tet4 do)",
                    mesh.kind.name()
                )));
            }
        };
    }
    if let Some(c) = sets {
        mesh.sets.merge(c.evaluate(&mesh, landmarks)?);
    }
    // Sets are evaluated in the reference frame (the sets file's axes), then the mesh is
    // carried to the data's frame and unit.
    if let Some(t) = frame {
        mesh.nodes = mesh.nodes.iter().map(|p| t.apply(p)).collect();
    }
    let q = mesh_quality(&mesh);
    write_mesh(output, &mesh, None, &q)
}

/// Repairs the mesh in `mesh` (untangling, then raising scaled Jacobians below the bound):
/// boundary nodes slide on the outline or surface in `surface` when given, else stay. Writes
/// the repaired mesh to `out` (format from the extension) and returns what the repair did; a
/// mesh with an element still inverted is an [`Error::Mesh`] and is not written.
pub fn repair_mesh_file(
    mesh: &Path,
    surface: Option<&Path>,
    params: &RepairParams,
    out: &Path,
    progress: &dyn Progress,
) -> Result<RepairReport> {
    match read_any_mesh(mesh)? {
        AnyMesh::Two(m) => {
            let s = match surface {
                Some(p) => {
                    let v = read_outlines(p, true)?;
                    Some(
                        v.into_iter()
                            .next()
                            .ok_or_else(|| Error::parse(p, 0, "no outline in the file"))?,
                    )
                }
                None => None,
            };
            repair(m, s.as_ref(), params, out, progress)
        }
        AnyMesh::Three(m) => {
            let s = surface.map(read_surface).transpose()?;
            repair(m, s.as_ref(), params, out, progress)
        }
    }
}

/// [`repair_mesh_file`] of a mesh of dimension `D`.
fn repair<const D: usize>(
    mut m: FeMesh<D>,
    surface: Option<&Shape<D>>,
    params: &RepairParams,
    out: &Path,
    progress: &dyn Progress,
) -> Result<RepairReport> {
    let index = surface.map(ClosestPointIndex::from_shape);
    let before = mesh_quality(&m);
    let step = "repair";
    progress.step_started(step);
    let (r, q) = repair_with_quality(&mut m, index.as_ref(), params, &before)?;
    progress.step_finished(step);
    if r.inverted_after > 0 {
        return Err(Error::Mesh(format!(
            "{}: {} element(s) still inverted after the repair ({} before; min scaled Jacobian {:.3} -> {:.3}); no mesh written",
            out.display(),
            r.inverted_after,
            r.inverted_before,
            r.scaled_jacobian_min_before,
            r.scaled_jacobian_min,
        )));
    }
    write_mesh(out, &m, None, &q)?;
    Ok(r)
}
