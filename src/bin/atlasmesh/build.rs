//! `atlasmesh build`: an atlas (shape model and mean mesh) from a population, saved.

use crate::args::{PopArgs, RunArgs};
use crate::population::{Read, corresponded, read};
use crate::terminal::Terminal;
use atlasmesh::study::{self, Progress};
use clap::Args;
use std::path::PathBuf;

/// Arguments of `atlasmesh build`.
#[derive(Args)]
pub struct BuildArgs {
    #[command(flatten)]
    pop: PopArgs,
    #[command(flatten)]
    run: RunArgs,
    /// Atlas file to write (safetensors).
    #[arg(long)]
    out: PathBuf,
    /// Also measure the model's compactness, generalization and specificity (up to 30
    /// modes; 1000 random instances): ATLAS.measures.json and ATLAS.measures.png.
    #[arg(long)]
    measures: bool,
    /// The shape model alone (GPA, PCA; with --measures its measures), without a mean mesh:
    /// for populations that need none, 3D point sets in correspondence without faces
    /// included. `instance` and `sample` then write shapes only; `fit` needs a mesh.
    #[arg(long, conflicts_with = "template_mesh")]
    no_mesh: bool,
    /// For a cohort larger than the memory: surfaces already in correspondence (e.g.
    /// `register`'s registered.list) read from their files on each pass, a batch at a time;
    /// GPA in passes and the leading modes by a randomized PCA (the modes asked with --modes,
    /// or up to --max-modes with a share of variance). Memory: the mean, one batch and the
    /// modes, never the population.
    #[arg(long, conflicts_with_all = ["template_mesh", "measures", "register", "landmarks", "cut"])]
    stream: bool,
    /// With --stream: shapes read at a time.
    #[arg(long, value_name = "N", requires = "stream", default_value_t = 256, value_parser = crate::args::count::<1, 1_000_000>)]
    batch: usize,
    /// With --stream and a share of variance (--variance, or the default 0.985): the most
    /// modes computed; the share must be reached within them.
    #[arg(long, value_name = "M", requires = "stream", default_value_t = 100, value_parser = crate::args::count::<1, 10_000>)]
    max_modes: usize,
}

/// Runs `atlasmesh build`.
pub fn run(mut a: BuildArgs, term: &Terminal) -> anyhow::Result<()> {
    let unused = a.run.fit_options_given();
    if !unused.is_empty() {
        return Err(atlasmesh::Error::Parameter(format!(
            "build does not use {}: {} of a subject's fit (`atlasmesh fit`, `loo`); \
             build writes the mean mesh as ATLAS_mean_mesh.vtu, and `atlasmesh convert ATLAS \
             mean.inp` writes it in another format",
            unused.join(", "),
            if unused.len() == 1 {
                "an option"
            } else {
                "options"
            }
        ))
        .into());
    }
    a.pop.expand()?;
    if a.stream {
        return streamed(&a, term);
    }
    if study::inputs_are_surfaces(&a.pop.shapes)? {
        build(&a, read::<3>(&a.pop, &a.run, a.no_mesh, term)?, term)
    } else {
        build(&a, read::<2>(&a.pop, &a.run, false, term)?, term)
    }
}

/// `atlasmesh build` on shapes of either dimension.
fn build<const D: usize>(a: &BuildArgs, mut pop: Read<D>, term: &Terminal) -> anyhow::Result<()> {
    let (shapes, template) = corresponded(&mut pop, 0, term)?;
    let Read {
        population:
            atlasmesh::study::Population {
                inputs,
                meshes,
                landmark_ids,
                ..
            },
        params,
        ..
    } = pop;
    let meshes = meshes.as_deref();
    let params = &params;
    let step = if a.no_mesh {
        "shape model (GPA, PCA)"
    } else {
        "atlas (GPA, PCA, mesh of the mean)"
    };
    term.step_started(step);
    let atlas = if a.no_mesh {
        study::build_model(&shapes, params, &landmark_ids, &a.out)?
    } else {
        let cut = study::cut_facets(&shapes, &inputs);
        study::build_with_meshes(&shapes, meshes, params, &landmark_ids, &cut, &a.out).map_err(|e| match e {
            atlasmesh::Error::Mesh(m) => atlasmesh::Error::Mesh(format!(
                "{m}; the shape model itself was built: save it without a mean mesh with --no-mesh, or mesh the mean with another --element-size or a --template-mesh"
            )),
            e => e,
        })?
    };
    term.step_finished(step);
    if a.measures {
        let step = "compactness, generalization, specificity (1000 instances per mode count)";
        term.step_started(step);
        let (m, json) = study::write_model_measures(&shapes, &a.out, params.plots)?;
        term.step_finished(step);
        let k = m.modes.len().min(atlas.num_modes()).max(1) - 1;
        println!(
            "measures ({} modes): compactness {:.4}, generalization {:.4} ± {:.4}, specificity {:.4} ± {:.4} (shape units): {}",
            k + 1,
            m.compactness[k],
            m.generalization[k],
            m.generalization_sd[k],
            m.specificity[k],
            m.specificity_sd[k],
            json.display()
        );
    }
    let m = atlas.num_modes();
    let unit = study::data_per_mean(&shapes, &atlas.mean_shape());
    let mesh = if atlas.has_mesh() {
        format!(
            "mean mesh {} {} elements of size {:.3} in the shapes' unit ({:.2} % of the largest extent)",
            atlas.mesh.num_elements(),
            atlas.mesh.kind.name(),
            atlas.params.element_size * unit,
            100.0 * atlas.params.element_size
        )
    } else {
        "no mean mesh".to_string()
    };
    println!(
        "atlas: {} ({} shapes, {} points, {m} modes explaining {:.4} of the variance, {mesh})",
        a.out.display(),
        shapes.len(),
        atlas.mean.len(),
        atlas.cumulative_variance[m - 1],
    );
    let facts = study::write_build_facts(&a.out, &inputs, template.as_deref(), &atlas, unit)?;
    println!("inputs and registration: {}", facts.display());
    Ok(())
}

/// `atlasmesh build --stream`: the atlas of surfaces in correspondence read from their files
/// on each pass.
fn streamed(a: &BuildArgs, term: &Terminal) -> anyhow::Result<()> {
    if let Some(image) = a
        .pop
        .shapes
        .iter()
        .find(|p| atlasmesh::formats::is_image_file(p))
    {
        return Err(atlasmesh::Error::Parameter(format!(
            "{}: a label map; --stream reads surfaces in correspondence: put the label maps in \
             correspondence first (`atlasmesh register`) and stream its registered.list",
            image.display()
        ))
        .into());
    }
    if !study::inputs_are_surfaces(&a.pop.shapes)? {
        return Err(atlasmesh::Error::Parameter(
            "--stream reads 3D surfaces in correspondence (PLY, STL, OBJ, VTK, VTP); build 2D \
             outlines without it"
                .into(),
        )
        .into());
    }
    let mut params = a.run.params_for(3)?;
    crate::args::apply_pop(&mut params, &a.pop);
    let stream = atlasmesh::model::StreamParams {
        batch: a.batch,
        max_modes: a.max_modes,
        ..Default::default()
    };
    let files = study::SurfaceFiles::new(a.pop.shapes.clone())?;
    let step = format!(
        "streamed atlas of {} surfaces, {} at a time (GPA in passes, randomized PCA{})",
        a.pop.shapes.len(),
        a.batch,
        if a.no_mesh { "" } else { ", mesh of the mean" }
    );
    term.step_started(&step);
    let atlas = study::build_streamed(&files, &params, &stream, a.no_mesh, &a.out)?;
    term.step_finished(&step);
    let m = atlas.num_modes();
    let unit = atlas.data_frame.as_ref().map_or(f64::NAN, |f| f.s);
    println!(
        "atlas: {} ({} shapes, {} points, {m} modes explaining {:.4} of the variance, {})",
        a.out.display(),
        atlas.training_shapes,
        atlas.mean.len(),
        atlas.cumulative_variance[m - 1],
        if atlas.has_mesh() {
            format!(
                "mean mesh {} {} elements of size {:.3} in the shapes' unit",
                atlas.mesh.num_elements(),
                atlas.mesh.kind.name(),
                atlas.params.element_size * unit
            )
        } else {
            "no mean mesh".to_string()
        }
    );
    let facts = study::write_build_facts(&a.out, &[], None, &atlas, unit)?;
    if atlas.has_mesh() {
        println!("the mean mesh's figures: {}", facts.display());
    }
    Ok(())
}
