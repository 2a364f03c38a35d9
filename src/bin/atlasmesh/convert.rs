//! `atlasmesh convert`: an FE mesh (or an atlas's mean mesh) in another format.

use clap::Args;
use std::path::PathBuf;

/// Arguments of `atlasmesh convert`.
#[derive(Args)]
pub struct ConvertArgs {
    /// Input mesh or atlas.
    input: PathBuf,
    /// Output file (format from the extension).
    output: PathBuf,
    /// Sets (TOML) to add, evaluated on the input mesh.
    #[arg(long, value_name = "TOML")]
    sets: Option<PathBuf>,
    /// Write quadratic elements (hex8 to hex20, tet4 to tet10: a node in the middle of
    /// every edge). As a template (`--template-mesh`) the mid-edge nodes are morphed with
    /// the rest, so the edges follow the subject.
    #[arg(long)]
    quadratic: bool,
}

/// Runs `atlasmesh convert`.
pub fn run(a: ConvertArgs) -> anyhow::Result<()> {
    let sets = a
        .sets
        .map(|f| atlasmesh::mesh::SetsConfig::read(&f))
        .transpose()?;
    atlasmesh::study::convert_mesh_file(&a.input, &a.output, sets.as_ref(), a.quadratic)?;
    println!("{} -> {}", a.input.display(), a.output.display());
    Ok(())
}
