//! `atlasmesh repair`: inverted and poor elements of a mesh file repaired.

use crate::terminal::Terminal;
use atlasmesh::mesh::RepairParams;
use clap::Args;
use std::path::PathBuf;

/// Arguments of `atlasmesh repair`.
#[derive(Args)]
pub struct RepairArgs {
    /// The mesh (.inp, .msh, .vtu, .vtk).
    mesh: PathBuf,
    /// The surface (3D: PLY, STL, OBJ, VTK, VTP) or outline (2D) the boundary lies on.
    #[arg(long)]
    surface: Option<PathBuf>,
    /// Scaled-Jacobian bound (default: hexahedra 0.2, quadrilaterals 0.3).
    #[arg(long, value_name = "SJ")]
    bound: Option<f64>,
    /// Output mesh (format from the extension).
    #[arg(long)]
    out: PathBuf,
}

/// Runs `atlasmesh repair`; an error (exit 4, nothing written) when an element stays
/// inverted.
pub fn run(a: RepairArgs, term: &Terminal) -> anyhow::Result<()> {
    let params = RepairParams {
        bound: a.bound,
        ..Default::default()
    };
    let r =
        atlasmesh::study::repair_mesh_file(&a.mesh, a.surface.as_deref(), &params, &a.out, term)?;
    println!(
        "{}: {} inverted and {} below {} before; {} inverted, {} below after (min scaled Jacobian {:.3} -> {:.3}); {} nodes moved, surface distance change {:.2e}; {}",
        a.mesh.display(),
        r.inverted_before,
        r.below_bound_before,
        r.bound,
        r.inverted_after,
        r.below_bound_after,
        r.scaled_jacobian_min_before,
        r.scaled_jacobian_min,
        r.moved_nodes,
        r.surface_distance_change,
        a.out.display()
    );
    Ok(())
}
