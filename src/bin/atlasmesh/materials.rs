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
    /// A load case (TOML; see docs/validation.md): node sets by geometry, displacements and
    /// forces, written into the .inp deck (and the .feb file) as a static step.
    #[arg(long, value_name = "FILE")]
    load: Option<PathBuf>,
    /// Solve the deck with CalculiX (ccx on the PATH, or ATLASMESH_CCX) and report the
    /// reactions and the stiffness; without CalculiX the deck is written and the report says
    /// how to run it. Needs --load.
    #[arg(long, requires = "load")]
    solve: bool,
    /// Solver threads (default: the cores available).
    #[arg(long, value_name = "N")]
    threads: Option<usize>,
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
    let load = atlasmesh::study::LoadRequest {
        load_case: a
            .load
            .as_ref()
            .map(|f| atlasmesh::mesh::LoadCase::read(f))
            .transpose()?,
        solve: a.solve,
        threads: a.threads.unwrap_or_else(|| {
            std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get)
        }),
    };
    if !a.ct.exists() {
        return Err(atlasmesh::Error::io(&a.ct, std::io::ErrorKind::NotFound.into()).into());
    }
    // A folder made here is removed again when the mesh or the CT is refused: a failed run
    // leaves nothing behind (a folder that was there stays).
    let made = !a.out.exists();
    std::fs::create_dir_all(&a.out).map_err(|e| atlasmesh::Error::io(&a.out, e))?;
    let r = atlasmesh::study::map_mesh_file(
        &a.mesh,
        &a.ct,
        &recipe,
        &formats,
        !a.no_plots,
        &load,
        &a.out,
    )
    .inspect_err(|_| {
        if made {
            let _ = std::fs::remove_dir_all(&a.out);
        }
    })?;
    print_summary(&a, &r);
    println!(
        "{}",
        safe(&format!("report: {}", a.out.join("report.json").display()))
    );
    Ok(())
}

/// The warnings, the summary line and the stiffness of a run.
fn print_summary(a: &MaterialsArgs, r: &atlasmesh::study::MaterialsReport) {
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
    // An image of density holds its unit, not HU.
    let value = match m.calibration.unit {
        Some(u) if m.calibration.image == atlasmesh::materials::ImageValues::Density => {
            format!("mean density {:.1} {}", m.mean_hu, u.name())
        }
        _ => format!("mean HU {:.1}", m.mean_hu),
    };
    let parts: String = m
        .parts
        .iter()
        .map(|p| {
            format!(
                " and {} {} elements of {}",
                p.elements, r.element_kind, p.name
            )
        })
        .collect();
    let line = format!(
        "{}: {} {} elements mapped on {}{parts}; {value} (volume-weighted); E {:.0} to {:.0} MPa \
         (median {:.0}) in {} materials{metal}; {} warnings",
        a.mesh.display(),
        m.elements,
        r.element_kind,
        a.ct.display(),
        m.modulus_min,
        m.modulus_max,
        m.modulus_median,
        m.materials,
        m.warnings.len()
    );
    println!("{}", safe(&line));
    if let Some(s) = &r.solve {
        println!(
            "{}",
            safe(&format!(
                "stiffness: {:.0} N/mm (reaction {:.1} N on {} at {} mm along {}; CalculiX {:.1} \
                 s, {:.0} MB)",
                s.stiffness_n_per_mm,
                s.reaction_n,
                s.loaded_set,
                s.displacement_mm,
                s.axis,
                s.seconds,
                s.peak_memory_mb
            ))
        );
    }
}
