//! `atlasmesh convert`: an FE mesh (or an atlas's mean mesh) in another format; a label
//! map's label as a surface.

use crate::terminal::safe;
use clap::Args;
use std::path::PathBuf;

/// Arguments of `atlasmesh convert`.
#[derive(Args)]
pub struct ConvertArgs {
    /// Input mesh or atlas, or a label map (NIfTI, NRRD, MetaImage) with --label.
    input: PathBuf,
    /// Output file (format from the extension; a label's surface: .ply, .stl, .vtp, .vtk).
    output: PathBuf,
    /// The label(s) of a label map whose surface is written: a number (31), several as one
    /// shape (1,7), or a name from --label-table or the file's segment names.
    #[arg(long, value_name = "LABEL")]
    label: Option<atlasmesh::image::LabelChoice>,
    /// Names of the labels: a CSV of `label,name` rows (e.g. TotalSegmentator's classes).
    #[arg(long, value_name = "CSV")]
    label_table: Option<PathBuf>,
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
    if atlasmesh::formats::is_image_file(&a.input) {
        let reading = atlasmesh::study::LabelReading::new(a.label, a.label_table.as_deref())?;
        let s = atlasmesh::study::convert_label_map(&a.input, &a.output, &reading)?;
        for w in &s.warnings {
            eprintln!("warning: {}", safe(&format!("{}: {w}", a.input.display())));
        }
        println!(
            "{}",
            safe(&format!(
                "{} -> {} ({} points, {} triangles, {} voxels{})",
                a.input.display(),
                a.output.display(),
                s.shape.points.len(),
                s.shape.facets.len(),
                s.voxels,
                if s.partial {
                    "; open where the image cuts it"
                } else {
                    ""
                }
            ))
        );
        return Ok(());
    }
    if a.label.is_some() || a.label_table.is_some() {
        anyhow::bail!(
            "{}: --label and --label-table are for label maps (.nii, .nii.gz, .nrrd, .nhdr, .mha, .mhd)",
            a.input.display()
        );
    }
    let sets = a
        .sets
        .map(|f| atlasmesh::mesh::SetsConfig::read(&f))
        .transpose()?;
    atlasmesh::study::convert_mesh_file(&a.input, &a.output, sets.as_ref(), a.quadratic)?;
    println!(
        "{}",
        safe(&format!("{} -> {}", a.input.display(), a.output.display()))
    );
    Ok(())
}
