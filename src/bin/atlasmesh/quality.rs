//! `atlasmesh quality`: the element quality of a mesh file (section 5.3).

use clap::Args;
use std::path::PathBuf;

/// Arguments of `atlasmesh quality`.
#[derive(Args)]
pub struct QualityArgs {
    /// The mesh file.
    mesh: PathBuf,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

/// Runs `atlasmesh quality`; an error (exit 4) when an element is inverted.
pub fn run(a: QualityArgs) -> anyhow::Result<()> {
    let d = atlasmesh::study::mesh_file_quality(&a.mesh)?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&d)?);
    } else {
        println!(
            "{}: {} elements; Jacobian min {:.4e}, 1 % {:.4e}, 5 % {:.4e}; scaled Jacobian min {:.4}, 1 % {:.4}, 5 % {:.4}; {} below {}; {} inverted; largest edge ratio {:.2}",
            a.mesh.display(),
            d.elements,
            d.jacobian_min,
            d.jacobian_p01,
            d.jacobian_p05,
            d.scaled_jacobian_min,
            d.scaled_jacobian_p01,
            d.scaled_jacobian_p05,
            d.elements_below_bound,
            d.bound,
            d.inverted_elements,
            d.edge_ratio_max
        );
    }
    if d.inverted_elements > 0 {
        return Err(atlasmesh::Error::Mesh(format!(
            "{}: {} inverted elements",
            a.mesh.display(),
            d.inverted_elements
        ))
        .into());
    }
    Ok(())
}
