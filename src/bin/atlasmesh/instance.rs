//! `atlasmesh instance`: shapes of the model for given weights, each with its FE mesh.

use crate::args::RunArgs;
use atlasmesh::model::Atlas;
use atlasmesh::study::{self, InstanceSpec};
use clap::Args;
use std::path::PathBuf;

/// Arguments of `atlasmesh instance`.
#[derive(Args)]
pub struct InstanceArgs {
    /// Atlas file written by `atlasmesh build`.
    #[arg(long)]
    atlas: PathBuf,
    /// Weights in standard deviations by mode (1-based), e.g. `1=+2,3=-1.5`; other modes 0.
    #[arg(long, conflicts_with = "mode")]
    weights: Option<String>,
    /// A sweep of one mode (1-based) over `--steps`.
    #[arg(long, requires = "steps")]
    mode: Option<usize>,
    /// The sweep's weights in standard deviations, `FROM:TO:STEP`, e.g. `-3:3:1`.
    #[arg(long, allow_hyphen_values = true)]
    steps: Option<String>,
    #[command(flatten)]
    run: RunArgs,
    /// Output folder: one folder per instance, and instances.json.
    #[arg(long)]
    out: PathBuf,
}

/// The instances asked for by `--weights` or `--mode` with `--steps`.
fn specs(a: &InstanceArgs) -> atlasmesh::Result<Vec<InstanceSpec>> {
    let bad = |m: String| atlasmesh::Error::Parameter(m);
    let number = |s: &str, what: &str| -> atlasmesh::Result<f64> {
        s.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite() && v.abs() <= 10.0)
            .ok_or_else(|| {
                bad(format!(
                    "{what}: {s:?} is not a number of standard deviations within ±10"
                ))
            })
    };
    let mode = |s: &str, what: &str| -> atlasmesh::Result<usize> {
        s.trim()
            .parse::<usize>()
            .ok()
            .filter(|&m| (1..=10_000).contains(&m))
            .ok_or_else(|| bad(format!("{what}: {s:?} is not a mode number (1, 2, ...)")))
    };
    if let Some(w) = &a.weights {
        let mut sd = Vec::new();
        for item in w.split(',').filter(|s| !s.trim().is_empty()) {
            let (m, v) = item
                .split_once('=')
                .ok_or_else(|| bad(format!("--weights: {item:?} is not MODE=SD (e.g. 1=+2)")))?;
            let m = mode(m, "--weights")?;
            if sd.len() < m {
                sd.resize(m, 0.0);
            }
            sd[m - 1] = number(v, "--weights")?;
        }
        let name = sd
            .iter()
            .enumerate()
            .filter(|(_, v)| **v != 0.0)
            .map(|(k, v)| format!("mode{}_{}", k + 1, sd_name(*v)))
            .collect::<Vec<_>>()
            .join("_");
        let name = if name.is_empty() {
            "mean".to_string()
        } else {
            name
        };
        return Ok(vec![InstanceSpec { name, sd }]);
    }
    let (Some(m), Some(steps)) = (a.mode, &a.steps) else {
        return Err(bad("give --weights, or --mode with --steps".into()));
    };
    let m = mode(&m.to_string(), "--mode")?;
    let p: Vec<&str> = steps.split(':').collect();
    if p.len() != 3 {
        return Err(bad(format!(
            "--steps {steps:?}: FROM:TO:STEP expected, e.g. -3:3:1"
        )));
    }
    let (from, to, step) = (
        number(p[0], "--steps")?,
        number(p[1], "--steps")?,
        number(p[2], "--steps")?,
    );
    if step <= 0.0 || to < from || (to - from) / step > 1000.0 {
        return Err(bad(format!(
            "--steps {steps:?}: FROM <= TO and STEP > 0, at most 1000 steps"
        )));
    }
    let n = ((to - from) / step + 1e-9).floor() as usize;
    Ok((0..=n)
        .map(|i| {
            let v = from + i as f64 * step;
            let mut sd = vec![0.0; m];
            sd[m - 1] = v;
            InstanceSpec {
                name: format!("mode{m}_{}", sd_name(v)),
                sd,
            }
        })
        .collect())
}

/// A weight in standard deviations as a file-name part: `plus2`, `minus1.5`, `0`.
fn sd_name(v: f64) -> String {
    let v = if v.abs() < 1e-12 { 0.0 } else { v };
    match v {
        v if v > 0.0 => format!("plus{v}"),
        v if v < 0.0 => format!("minus{}", -v),
        _ => "0".into(),
    }
}

/// Runs `atlasmesh instance`.
pub fn run(a: InstanceArgs) -> anyhow::Result<()> {
    let specs = specs(&a)?;
    if atlasmesh::formats::atlas_dimension(&a.atlas)? == 3 {
        instances::<3>(&a, &specs)
    } else {
        instances::<2>(&a, &specs)
    }
}

fn instances<const D: usize>(a: &InstanceArgs, specs: &[InstanceSpec]) -> anyhow::Result<()> {
    let atlas = Atlas::<D>::load(&a.atlas)?;
    if atlas.data_frame.is_none() {
        eprintln!(
            "warning: {} is an atlas of format version 2, which does not know its data's unit: the instances are in its reference frame (rebuild it to have them in the data's unit)",
            a.atlas.display()
        );
    }
    let params = a.run.params_for(D)?;
    let morpher = atlas.morpher(&params.morph)?;
    let reports = study::write_instances(&atlas, &morpher, specs, &params, &a.out)?;
    let json = serde_json::to_vec_pretty(&reports)?;
    atlasmesh::formats::write_atomic(&a.out.join("instances.json"), &json)?;
    for r in &reports {
        println!(
            "{}: scaled Jacobian min {:.3}, {} below the bound, boundary within {:.3} (RMS) of the surface, element size {:.3}",
            r.name,
            r.scaled_jacobian_min,
            r.elements_below_bound,
            r.mesh_rms_distance,
            r.element_size
        );
    }
    println!("instances: {}", a.out.join("instances.json").display());
    Ok(())
}
