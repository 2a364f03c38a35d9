//! Reading the population of `--shapes` with its landmarks, template meshes and parameters,
//! and putting it in correspondence (`--register`).

use crate::args::{PopArgs, RunArgs, apply_pop};
use crate::terminal::Terminal;
use atlasmesh::geometry::Shape;
use atlasmesh::mesh::FeMesh;
use atlasmesh::register::RegisterParams;
use atlasmesh::study::{self, PopulationOptions, RunParams};

/// The surfaces of `pop` (with their landmarks), the run parameters and the template meshes.
#[allow(clippy::type_complexity)]
pub fn surfaces_and_params(
    pop: &PopArgs,
    run: &RunArgs,
) -> anyhow::Result<(Vec<Shape<3>>, RunParams, Option<Vec<FeMesh<3>>>)> {
    let mut params = run.params()?;
    apply_pop(&mut params, pop);
    let mut shapes = study::load_surfaces(&pop.shapes)?;
    study::attach_landmarks(&mut shapes, &pop.landmarks)?;
    let meshes = if pop.template_mesh.is_empty() {
        None
    } else {
        Some(study::read_template_meshes(&pop.template_mesh)?)
    };
    Ok((shapes, params, meshes))
}

/// The outlines of `pop` (with their landmarks) and the run parameters.
pub fn outlines_and_params(
    pop: &PopArgs,
    run: &RunArgs,
) -> anyhow::Result<(Vec<Shape<2>>, RunParams)> {
    if !pop.template_mesh.is_empty() {
        return Err(atlasmesh::Error::Parameter(
            "--template-mesh applies to 3D surfaces; 2D outlines get the automatic quad mesh"
                .into(),
        )
        .into());
    }
    let mut params = run.params()?;
    apply_pop(&mut params, pop);
    let opts = PopulationOptions {
        closed: !pop.open,
        resample: pop.resample,
    };
    let mut shapes = if pop.register {
        study::load_outlines_raw(&pop.shapes, &opts)?
    } else {
        study::load_population(&pop.shapes, &opts)?
    };
    study::attach_landmarks(&mut shapes, &pop.landmarks)?;
    Ok((shapes, params))
}

/// The shapes in correspondence: registered to a template with `--register`, else as given.
pub fn corresponded<const D: usize>(
    pop: &PopArgs,
    shapes: &[Shape<D>],
    jobs: usize,
    term: &Terminal,
) -> anyhow::Result<Vec<Shape<D>>> {
    let mut params = RegisterParams::for_dimension(D);
    if let Some(g) = pop.register_grid {
        params.grid = g;
    }
    let register = pop.register.then_some((&params, pop.template.as_deref()));
    let (c, t) = study::correspond(shapes, register, jobs, term)?;
    if let Some(t) = t
        && !term.is_quiet()
    {
        eprintln!("registration template: {}", shapes[t].name);
    }
    Ok(c)
}
