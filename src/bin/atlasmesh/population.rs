//! Reading the population of `--shapes` with its landmarks, template meshes and parameters,
//! and putting it in correspondence (`--register`).

use crate::args::{PopArgs, RunArgs, apply_pop};
use crate::terminal::Terminal;
use atlasmesh::geometry::Shape;
use atlasmesh::mesh::FeMesh;
use atlasmesh::register::RegisterParams;
use atlasmesh::report::InputReport;
use atlasmesh::study::{self, PopulationOptions, RunParams, Template};
use std::path::Path;

/// A population as read: its shapes (islands dropped), what was found in them, the run
/// parameters and, in 3D, the template meshes.
pub struct Population<const D: usize> {
    /// The shapes with their landmarks.
    pub shapes: Vec<Shape<D>>,
    /// Topology and islands of each (registration residuals added by [`corresponded`]).
    pub inputs: Vec<InputReport>,
    /// The run's parameters.
    pub params: RunParams,
    /// `--template-mesh`, read.
    pub meshes: Option<Vec<FeMesh<D>>>,
    /// The landmark ids every shape has (in their order), for `--template-landmarks`.
    pub landmark_ids: Vec<String>,
    /// The shapes as read, before a common cut (`--cut`) cut and capped them: `loo` fits
    /// these, as `fit` would take them.
    pub as_read: Option<Vec<Shape<D>>>,
}

/// Drops the floating islands of `shapes` (or refuses them with `--refuse-islands`,
/// [`study::clean_population`]), with a warning for each on stderr.
fn clean<const D: usize>(
    pop: &PopArgs,
    shapes: &mut [Shape<D>],
    pairing: &study::LandmarkPairing,
    term: &Terminal,
) -> anyhow::Result<Vec<InputReport>> {
    let inputs = study::clean_population(shapes, pairing, pop.refuse_islands)?;
    if !term.is_quiet() {
        for i in &inputs {
            for w in &i.warnings {
                eprintln!("warning: {}: {w}", i.name);
            }
        }
    }
    Ok(inputs)
}

/// The surfaces of `pop` (with their landmarks), the run parameters and the template meshes.
pub fn surfaces_and_params(
    pop: &PopArgs,
    run: &RunArgs,
    point_sets: bool,
    term: &Terminal,
) -> anyhow::Result<Population<3>> {
    let mut params = run.params_for(3)?;
    apply_pop(&mut params, pop);
    let (mut shapes, notes) = if point_sets && !pop.register {
        let s = study::load_point_sets(&pop.shapes, &pop.columns.clone().unwrap_or_default())?;
        let n = vec![Vec::new(); s.len()];
        (s, n)
    } else {
        study::load_surfaces_noted(&pop.shapes, &pop.labels.reading()?)?
            .into_iter()
            .unzip()
    };
    let pairing = study::attach_landmarks(&mut shapes, &pop.landmarks)?;
    let mut inputs = clean(pop, &mut shapes, &pairing, term)?;
    // What the label maps' reading found, first.
    for (i, n) in inputs.iter_mut().zip(notes) {
        if !term.is_quiet() {
            for w in &n {
                eprintln!("warning: {}: {w}", i.name);
            }
        }
        i.warnings.splice(0..0, n);
    }
    let before = shapes.clone();
    let as_read = cut(pop, &mut shapes, &mut inputs, point_sets, term)?.then_some(before);
    let meshes = if pop.template_mesh.is_empty() {
        None
    } else {
        Some(study::read_template_meshes(&pop.template_mesh)?)
    };
    Ok(Population {
        shapes,
        inputs,
        params,
        meshes,
        landmark_ids: pairing.ids,
        as_read,
    })
}

/// The shapes put on a common cut ([`study::cut_population`]) as `--cut` asks; by default
/// (`auto`) when a shape is open where a plane cut it and a mesh is to be made. Whether they
/// were cut.
fn cut(
    pop: &PopArgs,
    shapes: &mut [Shape<3>],
    inputs: &mut [InputReport],
    point_sets: bool,
    term: &Terminal,
) -> anyhow::Result<bool> {
    let spec: study::CutSpec = match pop.cut.as_deref() {
        Some(c) if c.eq_ignore_ascii_case("none") => return Ok(false),
        Some(c) => c.parse()?,
        None if !point_sets && shapes.iter().any(study::is_cut_by_a_plane) => study::CutSpec::Auto,
        None => return Ok(false),
    };
    let length = study::cut_population(shapes, inputs, &spec)?;
    if !term.is_quiet() {
        eprintln!(
            "cut: every shape cut {length:.4} from its far end and closed by a flat cap{}",
            if pop.cut.is_none() {
                " (--cut auto: some shapes are open; --cut none keeps them as they are)"
            } else {
                ""
            }
        );
    }
    Ok(true)
}

/// The outlines of `pop` (with their landmarks) and the run parameters.
pub fn outlines_and_params(
    pop: &PopArgs,
    run: &RunArgs,
    term: &Terminal,
) -> anyhow::Result<Population<2>> {
    if !pop.template_mesh.is_empty() {
        return Err(atlasmesh::Error::Parameter(
            "--template-mesh applies to 3D surfaces; 2D outlines get the automatic quad mesh"
                .into(),
        )
        .into());
    }
    if pop.cut.is_some() {
        return Err(atlasmesh::Error::Parameter(
            "--cut applies to 3D surfaces; an open outline is meshed closed by the straight segment between its ends"
                .into(),
        )
        .into());
    }
    let mut params = run.params_for(2)?;
    apply_pop(&mut params, pop);
    let opts = PopulationOptions {
        closed: !pop.open,
        resample: pop.resample,
        columns: pop.columns.clone().unwrap_or_default(),
    };
    let mut shapes = if pop.register {
        study::load_outlines_raw(&pop.shapes, &opts)?
    } else {
        study::load_population(&pop.shapes, &opts)?
    };
    let pairing = study::attach_landmarks(&mut shapes, &pop.landmarks)?;
    let inputs = clean(pop, &mut shapes, &pairing, term)?;
    Ok(Population {
        shapes,
        inputs,
        params,
        meshes: None,
        landmark_ids: pairing.ids,
        as_read: None,
    })
}

/// The `--template` file, read in the population's dimension with its `--template-landmarks`.
fn template_file<const D: usize>(
    pop: &PopArgs,
    path: &Path,
    landmark_ids: &[String],
) -> anyhow::Result<Shape<D>> {
    let files = [path.to_path_buf()];
    let mut t: Shape<D> = if D == 3 {
        study::load_surfaces(&files, &pop.labels.reading()?)?
            .remove(0)
            .into_dim()
    } else {
        let opts = PopulationOptions {
            closed: !pop.open,
            resample: pop.resample,
            columns: pop.columns.clone().unwrap_or_default(),
        };
        study::load_outlines_raw(&files, &opts)?
            .remove(0)
            .into_dim()
    };
    if let Some(l) = &pop.template_landmarks {
        // Paired with the population's landmarks by id.
        let unused = study::attach_landmarks_paired(&mut t, l, landmark_ids)?;
        if !unused.is_empty() {
            eprintln!(
                "warning: template landmark(s) [{}] of {} are not in every shape and are not used",
                unused.join(", "),
                l.display()
            );
        }
    }
    Ok(t)
}

/// The shapes in correspondence: registered to a template with `--register`, else as given;
/// the registration's residuals go into `inputs` (with a warning where the template did not
/// reach). Returns the shapes and the template's name.
pub fn corresponded<const D: usize>(
    pop: &PopArgs,
    shapes: &[Shape<D>],
    landmark_ids: &[String],
    inputs: &mut [InputReport],
    jobs: usize,
    term: &Terminal,
) -> anyhow::Result<(Vec<Shape<D>>, Option<String>)> {
    let mut params = RegisterParams::for_dimension(D);
    if let Some(g) = pop.register_grid {
        params.grid = g;
    }
    let external: Option<Shape<D>> = match &pop.template {
        Some(t) if !shapes.iter().any(|s| &s.name == t) && Path::new(t).exists() => {
            Some(template_file(pop, Path::new(t), landmark_ids)?)
        }
        _ => None,
    };
    let template = match (&external, &pop.template) {
        (Some(t), _) => Template::External(t),
        (None, Some(name)) => Template::Member(name),
        (None, None) => Template::Nearest,
    };
    let register = pop.register.then_some((&params, template));
    let Some(r) = study::correspond(shapes, register, jobs, term)? else {
        return Ok((shapes.to_vec(), None));
    };
    if !term.is_quiet() {
        eprintln!("registration template: {}", r.template);
    }
    for (name, w) in study::record_registration(inputs, &r.residuals) {
        if !term.is_quiet() {
            eprintln!("warning: {name}: {w}");
        }
    }
    Ok((r.shapes, Some(r.template)))
}
