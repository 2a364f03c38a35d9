//! `--shapes` and how to read, cut and register them, as the library's population value
//! ([`study::PopulationSpec`], [`study::Population`]); what it says printed on stderr.

use crate::args::{PopArgs, RunArgs, apply_pop};
use crate::terminal::Terminal;
use atlasmesh::geometry::Shape;
use atlasmesh::study::{self, PopulationOptions, PopulationSpec, RunParams};

/// A population as read, with the run's parameters and the spec it was read by.
pub struct Read<const D: usize> {
    /// The population.
    pub population: study::Population<D>,
    /// The run's parameters.
    pub params: RunParams,
    /// What the population was read by (its registration too).
    pub spec: PopulationSpec,
}

/// The library's spec of `--shapes` and the options that read them; `point_sets`: 3D point
/// sets without faces (`build --no-mesh`).
fn spec(pop: &PopArgs, point_sets: bool) -> anyhow::Result<PopulationSpec> {
    Ok(PopulationSpec {
        shapes: pop.shapes.clone(),
        landmarks: pop.landmarks.clone(),
        template_meshes: pop.template_mesh.clone(),
        labels: pop.labels.reading()?,
        outlines: PopulationOptions {
            closed: !pop.open,
            resample: pop.resample,
            columns: pop.columns.clone().unwrap_or_default(),
        },
        point_sets,
        refuse_islands: pop.refuse_islands,
        cut: match pop.cut.as_deref() {
            Some(c) => c.parse()?,
            None => study::CutChoice::WhenOpen,
        },
        registration: pop.register.then(|| study::RegistrationSpec {
            grid: pop.register_grid,
            template: pop.template.clone(),
            template_landmarks: pop.template_landmarks.clone(),
        }),
    })
}

/// Reads the population of `pop` in dimension `D` (3: surfaces, or point sets with
/// `point_sets`; 2: outlines) with the run parameters of `run`; its warnings and notes on
/// stderr unless quiet.
pub fn read<const D: usize>(
    pop: &PopArgs,
    run: &RunArgs,
    point_sets: bool,
    term: &Terminal,
) -> anyhow::Result<Read<D>> {
    let mut params = run.params_for(D)?;
    apply_pop(&mut params, pop);
    let spec = spec(pop, point_sets)?;
    let population = spec.read::<D>()?;
    if !term.is_quiet() {
        for (name, w) in population.warnings() {
            eprintln!("warning: {name}: {w}");
        }
        for n in &population.notes {
            eprintln!("{n}");
        }
    }
    Ok(Read {
        population,
        params,
        spec,
    })
}

/// The shapes in correspondence ([`study::Population::corresponded`]), with the template
/// and the registration's warnings on stderr unless quiet. Returns the shapes and the
/// template's name.
pub fn corresponded<const D: usize>(
    read: &mut Read<D>,
    jobs: usize,
    term: &Terminal,
) -> anyhow::Result<(Vec<Shape<D>>, Option<String>)> {
    let c = read.population.corresponded(&read.spec, jobs, term)?;
    if !term.is_quiet() {
        if let Some(t) = &c.template {
            eprintln!("registration template: {t}");
        }
        for (name, w) in &c.warnings {
            eprintln!("warning: {name}: {w}");
        }
    }
    Ok((c.shapes, c.template))
}
