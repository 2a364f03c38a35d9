//! `atlasmesh materials`: any FE mesh's bone materials from a CT (Bonemat's use: a mesh made
//! elsewhere).

use crate::terminal::safe;
use clap::Args;
use std::path::PathBuf;

/// Arguments of `atlasmesh materials`.
#[derive(Args)]
pub struct MaterialsArgs {
    /// The mesh (.inp, .msh, .vtu, .vtk; hexahedra, tetrahedra, linear or quadratic, or
    /// quadrilaterals over a one-slice image), in the CT's frame (mm).
    #[arg(long)]
    mesh: PathBuf,
    /// The CT: NIfTI, NRRD, MetaImage, or a DICOM series' folder.
    #[arg(long)]
    ct: PathBuf,
    /// The material recipe (TOML; see docs/materials.md); without it, the documented
    /// defaults.
    #[arg(long, value_name = "FILE")]
    recipe: Option<PathBuf>,
    /// Formats written, comma-separated: inp (a material per group of E), feb, vtu, vtk,
    /// msh (per-element HU, density, E).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "inp,vtu",
        value_name = "FORMATS"
    )]
    format: Vec<String>,
    /// No histogram picture.
    #[arg(long)]
    no_plots: bool,
    /// Output folder: NAME_materials.EXT, NAME_E.png, report.json.
    #[arg(long)]
    out: PathBuf,
}

/// Runs `atlasmesh materials`.
pub fn run(a: MaterialsArgs) -> anyhow::Result<()> {
    let formats = a
        .format
        .iter()
        .map(|f| {
            atlasmesh::formats::MeshFormat::parse(f).ok_or_else(|| {
                atlasmesh::Error::Parameter(format!("--format {f}: use inp, feb, vtu, vtk or msh"))
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    let recipe = match &a.recipe {
        Some(r) => atlasmesh::study::read_recipe(r)?,
        None => Default::default(),
    };
    // The inputs are read and checked before the output folder is made.
    recipe.law()?;
    if !a.ct.exists() {
        return Err(atlasmesh::Error::io(&a.ct, std::io::ErrorKind::NotFound.into()).into());
    }
    // A folder made here is removed again when the mesh or the CT is refused: a failed run
    // leaves nothing behind (a folder that was there stays).
    let made = !a.out.exists();
    std::fs::create_dir_all(&a.out).map_err(|e| atlasmesh::Error::io(&a.out, e))?;
    let r = atlasmesh::study::map_mesh_file(&a.mesh, &a.ct, &recipe, &formats, !a.no_plots, &a.out)
        .inspect_err(|_| {
            if made {
                let _ = std::fs::remove_dir_all(&a.out);
            }
        })?;
    let m = &r.materials;
    for w in &m.warnings {
        eprintln!("warning: {}", safe(w));
    }
    let metal = if m.metal_elements > 0 {
        format!(
            "; METAL in {} elements (up to {:.0} HU)",
            m.metal_elements, m.hu_max
        )
    } else {
        String::new()
    };
    let line = format!(
        "{}: {} {} elements mapped on {}; mean HU {:.1} (volume-weighted); E {:.0} to {:.0} MPa \
         (median {:.0}) in {} materials{metal}; {} warnings",
        a.mesh.display(),
        m.elements,
        r.element_kind,
        a.ct.display(),
        m.mean_hu,
        m.modulus_min,
        m.modulus_max,
        m.modulus_median,
        m.materials,
        m.warnings.len()
    );
    println!("{}", safe(&line));
    println!(
        "{}",
        safe(&format!("report: {}", a.out.join("report.json").display()))
    );
    Ok(())
}
