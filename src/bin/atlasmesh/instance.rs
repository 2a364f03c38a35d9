//! `atlasmesh instance` and `atlasmesh sample`: shapes of the model for given or random
//! weights, each with its FE mesh.

use crate::args::RunArgs;
use crate::terminal::Terminal;
use atlasmesh::model::Atlas;
use atlasmesh::report::Sampling;
use atlasmesh::study::{self, InstanceSpec, RunContext, RunPlace, Shard};
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
    /// Output folder: one folder per instance, instances.json and instances.html.
    #[arg(long)]
    out: PathBuf,
    /// Make every instance again, even those whose outputs are complete.
    #[arg(long)]
    no_resume: bool,
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
pub fn run(a: InstanceArgs, term: &Terminal) -> anyhow::Result<()> {
    let specs = specs(&a)?;
    let out = Outputs {
        atlas: &a.atlas,
        run: &a.run,
        out: &a.out,
        jobs: 0,
        shard: None,
        resume: !a.no_resume,
    };
    if atlasmesh::formats::atlas_dimension(&a.atlas)? == 3 {
        instances::<3>(&out, &|_| Ok((specs.clone(), None)), term)
    } else {
        instances::<2>(&out, &|_| Ok((specs.clone(), None)), term)
    }
}

/// Arguments of `atlasmesh sample`.
#[derive(Args)]
pub struct SampleArgs {
    /// Atlas file written by `atlasmesh build`.
    #[arg(long)]
    atlas: PathBuf,
    /// Samples to draw.
    #[arg(long, value_parser = crate::args::count::<1, 1_000_000>)]
    n: usize,
    /// Seed of the random stream: the same seed, count and atlas give the same samples.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Draw every weight within this many standard deviations (a truncated normal), e.g. 3.
    #[arg(long, value_name = "K")]
    max_sd: Option<f64>,
    #[command(flatten)]
    run: RunArgs,
    /// Output folder: one folder per sample, instances.json and instances.html.
    #[arg(long)]
    out: PathBuf,
    /// Worker threads (0 = all cores).
    #[arg(long, default_value_t = 0, value_parser = crate::args::count::<0, 1024>)]
    jobs: usize,
    /// Only the I-th of N parts of the samples (sample k to part k mod N), each into its own
    /// --out; join the parts' instances.json with `atlasmesh merge-reports`.
    #[arg(long, value_name = "I/N")]
    shard: Option<String>,
    /// Make every sample again, even those whose outputs are complete.
    #[arg(long)]
    no_resume: bool,
}

/// Runs `atlasmesh sample`.
pub fn run_sample(a: SampleArgs, term: &Terminal) -> anyhow::Result<()> {
    let shard = a.shard.as_deref().map(Shard::parse).transpose()?;
    let out = Outputs {
        atlas: &a.atlas,
        run: &a.run,
        out: &a.out,
        jobs: a.jobs,
        shard,
        resume: !a.no_resume,
    };
    if atlasmesh::formats::atlas_dimension(&a.atlas)? == 3 {
        instances::<3>(&out, &|atlas| sampled(&a, atlas), term)
    } else {
        instances::<2>(&out, &|atlas| sampled(&a, atlas), term)
    }
}

/// The samples `sample` asks of `atlas`, and how they were drawn.
fn sampled<const D: usize>(
    a: &SampleArgs,
    atlas: &Atlas<D>,
) -> atlasmesh::Result<(Vec<InstanceSpec>, Option<Sampling>)> {
    let specs = study::sample_specs(atlas, a.n, a.seed, a.max_sd)?;
    let sampling = Sampling {
        n: a.n,
        seed: a.seed,
        max_sd: a.max_sd,
    };
    Ok((specs, Some(sampling)))
}

/// What `instance` and `sample` share: the atlas, the run's options and the outputs.
struct Outputs<'a> {
    atlas: &'a PathBuf,
    run: &'a RunArgs,
    out: &'a PathBuf,
    jobs: usize,
    shard: Option<Shard>,
    resume: bool,
}

/// The instances' specs of an atlas, and how they were drawn.
type SpecsOf<'a, const D: usize> =
    dyn Fn(&Atlas<D>) -> atlasmesh::Result<(Vec<InstanceSpec>, Option<Sampling>)> + 'a;

fn instances<const D: usize>(
    o: &Outputs,
    specs: &SpecsOf<D>,
    term: &Terminal,
) -> anyhow::Result<()> {
    let place = RunPlace {
        out: o.out.clone(),
        resume: o.resume,
        shard: o.shard,
    };
    let ctx = RunContext::<D>::open(o.atlas, o.run.params()?, o.run.deck.as_deref(), place)?;
    let atlas = &ctx.atlas;
    if atlas.data_frame.is_none() && !term.is_quiet() {
        eprintln!(
            "warning: {} is an atlas of format version 2, which does not know its data's unit: the instances are in its reference frame (rebuild it to have them in the data's unit)",
            o.atlas.display()
        );
    }
    let (specs, sampling) = specs(atlas)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(o.jobs)
        .build()
        .map_err(|e| anyhow::anyhow!("thread pool: {e}"))?;
    let r = pool.install(|| study::write_instances(&ctx, &specs, sampling, term))?;
    if !atlas.has_mesh() {
        println!(
            "{} shapes written ({} already complete): the atlas has no mean mesh (built with --no-mesh), so no FE mesh",
            r.summary.written, r.summary.resumed
        );
        println!("instances: {}", o.out.join("instances.json").display());
        return Ok(());
    }
    let unit = if r.data_unit {
        ""
    } else {
        " (reference frame)"
    };
    if r.instances.len() <= 20 {
        for i in &r.instances {
            println!(
                "{}: scaled Jacobian min {:.3}, {} below the bound, boundary within {:.3}{unit} (RMS) of the surface, element size {:.3}",
                i.name,
                i.scaled_jacobian_min,
                i.elements_below_bound,
                i.mesh_rms_distance,
                i.element_size
            );
        }
    }
    let s = &r.summary;
    println!(
        "{} instances written ({} already complete), {} failed; smallest scaled Jacobian {:.3}, {} with elements below the repair bound; boundary nodes within {:.2} % of the element size of the surface (RMS, largest), faces within {:.2} %",
        s.written,
        s.resumed,
        s.failed,
        s.scaled_jacobian_min,
        s.below_repair_bound,
        100.0 * s.boundary_node_rms_distance_per_element_max,
        100.0 * s.mesh_rms_distance_per_element_max
    );
    for f in &r.failed {
        eprintln!("failed: {}: {}", f.name, f.error);
    }
    println!("instances: {}", o.out.join("instances.json").display());
    if s.failed > 0 {
        return Err(crate::summary::BatchFailed {
            failed: s.failed,
            total: s.failed + s.written,
            items: "instances",
            report: "instances.json",
        }
        .into());
    }
    Ok(())
}
