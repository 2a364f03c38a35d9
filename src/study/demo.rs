//! The built-in demo: synthetic populations, an atlas, leave-one-out fits.

use super::batch::fit_shapes;
use super::build::build;
use super::params::RunParams;
use super::progress::Progress;
use super::run::{RunContext, RunPlace};
use super::subject_file::prepare_subject;
use crate::error::{Error, Result};
use crate::formats::create_dir;
use crate::geometry::{Point, Shape, Similarity};
use crate::model::Atlas;
use crate::register::resample_corresponding;
use crate::report::Report;
use std::path::Path;

/// The demo's synthetic population: `n` closed outlines of an asymmetric bone-like section
/// with four independent modes of variation (elongation, a lobe, a bend, a notch), each in a
/// random similarity pose. Points correspond (same parameter values on every shape).
pub fn demo_population(n: usize, points: usize, seed: u64) -> Vec<Shape<2>> {
    use rand::{RngExt, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|k| {
            let c: [f64; 4] = std::array::from_fn(|_| crate::model::standard_normal(&mut rng));
            let mut pose = Similarity::<2>::planar_rotation(rng.random_range(-0.6..0.6));
            pose.s = rng.random_range(20.0..60.0);
            pose.t = [
                rng.random_range(-100.0..100.0),
                rng.random_range(-100.0..100.0),
            ];
            let pts = (0..points)
                .map(|i| {
                    let t = i as f64 / points as f64 * std::f64::consts::TAU;
                    let lobe = 0.18 * (-((t - 1.2) / 0.45).powi(2)).exp();
                    let notch = -0.1 * (-((t - 4.0) / 0.3).powi(2)).exp();
                    let r = 1.0
                        + 0.3 * t.cos()
                        + lobe * (1.0 + 0.35 * c[1])
                        + notch * (1.0 + 0.4 * c[3]);
                    let x = r * t.cos() * (1.0 + 0.08 * c[0]);
                    let y = r * t.sin() * 0.7 + 0.06 * c[2] * x * x;
                    pose.apply(&[x, y])
                })
                .collect();
            Shape::polyline(format!("demo-{k:02}"), pts, true)
        })
        .collect()
}

/// The 3D demo's synthetic population: `n` closed surfaces (a triangulated sphere of
/// `rings × 2 rings` vertices, deformed) with four independent modes of variation (length,
/// a condyle-like lobe, a bend, a flattening), each in a random similarity pose. Vertices
/// correspond (same parameters on every shape).
pub fn demo_population_3d(n: usize, rings: usize, seed: u64) -> Result<Vec<Shape<3>>> {
    use rand::{RngExt, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let nu = 2 * rings;
    let nv = rings;
    (0..n)
        .map(|k| {
            let c: [f64; 4] = std::array::from_fn(|_| crate::model::standard_normal(&mut rng));
            let axis = crate::geometry::normalize([
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            ]);
            let angle: f64 = rng.random_range(-0.5..0.5);
            let mut pose = Similarity::<3>::identity();
            pose.r = crate::geometry::rotation_exp::<3>(&crate::geometry::scale(axis, angle));
            pose.s = rng.random_range(10.0..40.0);
            pose.t = std::array::from_fn(|_| rng.random_range(-50.0..50.0));
            let shape_at = |th: f64, ph: f64| -> Point<3> {
                // Unit sphere direction.
                let d = [th.cos() * ph.cos(), th.cos() * ph.sin(), th.sin()];
                let lobe = 0.25
                    * (1.0 + 0.4 * c[1])
                    * (-((d[0] - 0.7).powi(2) + (d[1] + 0.3).powi(2) + (d[2] - 0.5).powi(2))
                        / 0.15)
                        .exp();
                let r = 1.0 + lobe;
                let x = r * d[0] * (1.6 + 0.15 * c[0]);
                let y = r * d[1] * (0.8 + 0.06 * c[3]);
                let z = r * d[2] + 0.12 * c[2] * (x * x - 1.0);
                pose.apply(&[x, y, z])
            };
            let (points, facets) = crate::geometry::uv_sphere(nu, nv, shape_at);
            crate::geometry::prepare_surface(Shape {
                name: format!("demo3d-{k:02}"),
                points,
                facets,
                landmarks: Vec::new(),
            })
        })
        .collect()
}

/// The built-in 3D demo: a seeded synthetic population of closed surfaces, an atlas from 24
/// with an automatic hexahedral mesh of the mean, fits and morphs of the 6 held-out ones; all
/// outputs in `out`.
pub fn demo_3d(out: &Path, progress: &dyn Progress) -> Result<Report> {
    create_dir(out)?;
    let shapes = demo_population_3d(30, 24, 20261122)?;
    let (train, test) = shapes.split_at(24);
    let mut params = RunParams {
        element_size: crate::mesh::ElementSize::Share(0.05),
        ..RunParams::default()
    };
    params.atlas.modes = crate::model::ModeSelection::Variance(0.99);
    build(train, &params, &out.join("atlas.safetensors"))?;
    let loaded = Atlas::<3>::load(&out.join("atlas.safetensors"))?;
    let report = fit_held_out(
        loaded,
        params,
        test,
        "demo 3D (synthetic, seed 20261122)",
        out,
        progress,
    )?;
    demo_succeeded(report)
}

/// The built-in demo: a seeded synthetic population, an atlas from 24 shapes, fits and morphs
/// of the 6 held-out shapes, all outputs in `out`.
pub fn demo(out: &Path, progress: &dyn Progress) -> Result<Report> {
    create_dir(out)?;
    let population = demo_population(30, 180, 20261122);
    let (shapes, _) = resample_corresponding(&population, 400, true)?;
    let (train, test) = shapes.split_at(24);
    let params = RunParams {
        element_size: crate::mesh::ElementSize::Share(0.03),
        ..RunParams::default()
    };
    build(train, &params, &out.join("atlas.safetensors"))?;
    let loaded = Atlas::<2>::load(&out.join("atlas.safetensors"))?;
    let report = fit_held_out(
        loaded,
        params,
        test,
        "demo (synthetic, seed 20261122)",
        out,
        progress,
    )?;
    demo_succeeded(report)
}

/// The held-out shapes `test` fitted with `atlas` and written into `out` (`label` names the
/// data in the report).
fn fit_held_out<const D: usize>(
    atlas: Atlas<D>,
    params: RunParams,
    test: &[Shape<D>],
    label: &str,
    out: &Path,
    progress: &dyn Progress,
) -> Result<Report> {
    let place = RunPlace {
        out: out.to_path_buf(),
        ..RunPlace::default()
    };
    let ctx = RunContext::new(atlas, params, place)?;
    let subjects = test
        .iter()
        .map(|s| prepare_subject(s.clone(), Path::new(&s.name)))
        .collect::<Result<Vec<_>>>()?;
    fit_shapes(&ctx, &subjects, label, progress)
}

/// The demo's report, or an error when one of its subjects failed (every one succeeds on a
/// sound build).
fn demo_succeeded(report: Report) -> Result<Report> {
    match report.failed.first() {
        None => Ok(report),
        Some(f) => Err(Error::Numerical(format!(
            "demo subject {} failed: {}",
            f.name, f.error
        ))),
    }
}
