//! Atlases from shapes that are not in correspondence (section 2.1): the IMM hands given
//! uneven point counts and spacing, registered with their 56 landmarks, then the paper's
//! leave-one-out.

mod common;

use atlasmesh::geometry::{Shape, dist2};
use atlasmesh::model::ModeSelection;
use atlasmesh::pipeline::{
    PopulationOptions, RunParams, leave_one_out, leave_one_out_of, load_population,
    register_population,
};
use atlasmesh::register::RegisterParams;
use atlasmesh::resample::resample_uniform;
use rand::{RngExt, SeedableRng};

/// Hand `s` (an outline through its 56 landmarks) resampled to `n` points whose spacing
/// varies along the outline (a sinusoidal warp of arc length, phase `phase`), with the
/// landmarks as the indices of the points nearest to them.
fn uneven(s: &Shape<2>, n: usize, phase: f64, amp: f64) -> Shape<2> {
    let dense = resample_uniform(s, 8000, false).unwrap();
    let k = std::f64::consts::TAU * 3.0;
    let warp = |t: f64| {
        t + amp * ((k * t + phase).sin() - phase.sin() * (1.0 - t) - (k + phase).sin() * t) / k
    };
    let pts = (0..n)
        .map(|i| {
            let t = warp(i as f64 / (n - 1) as f64).clamp(0.0, 1.0);
            dense.points[(t * 7999.0).round() as usize]
        })
        .collect();
    let mut r = Shape::polyline(s.name.clone(), pts, false);
    r.landmarks = s
        .points
        .iter()
        .map(|q| {
            (0..r.points.len())
                .min_by(|&a, &b| dist2(r.points[a], *q).total_cmp(&dist2(r.points[b], *q)))
                .unwrap()
        })
        .collect();
    r
}

#[test]
fn hands_without_correspondence_register_and_fit() {
    let Some(data) = common::data_dir("hands_without_correspondence_register_and_fit") else {
        return;
    };
    let csv = data.join("imm-hands-2d/hands_long.csv");
    let landmarks = load_population(
        &[csv.clone()],
        &PopulationOptions {
            closed: false,
            resample: None,
        },
    )
    .unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2026);
    let raw: Vec<Shape<2>> = landmarks
        .iter()
        .map(|s| {
            let n = rng.random_range(1800..=2200);
            let phase = rng.random_range(0.0..std::f64::consts::TAU);
            uneven(s, n, phase, rng.random_range(0.2..0.5))
        })
        .collect();
    assert!(raw.iter().any(|s| s.points.len() != raw[0].points.len()));
    let (corresponded, template) =
        register_population(&raw, None, &RegisterParams::default(), 0, true).unwrap();
    eprintln!(
        "template: {} ({} points)",
        raw[template].name,
        raw[template].points.len()
    );
    let mut params = RunParams::default();
    params.atlas.modes = ModeSelection::Count(11);
    params.plots = false;
    let out = common::temp_dir("hands-raw");
    let r = leave_one_out_of(
        &corresponded,
        &raw,
        None,
        "raw hands",
        &params,
        &out,
        0,
        true,
    )
    .unwrap();
    // The same hands with the given correspondence (the issue-2 run).
    let given = load_population(
        &[csv],
        &PopulationOptions {
            closed: false,
            resample: Some(2001),
        },
    )
    .unwrap();
    let g = leave_one_out(&given, "hands", &params, &out.join("given"), 0, true).unwrap();
    eprintln!(
        "raw: {}/40 succeeded, {} valid, median normal correlation {:.3}; given correspondence: {:.3}",
        r.summary.succeeded,
        r.summary.meshes_valid,
        r.summary.median_normal_correlation,
        g.summary.median_normal_correlation
    );
    assert_eq!(r.summary.succeeded, 40);
    assert_eq!(r.summary.meshes_valid, 40);
    assert!(
        r.summary.median_normal_correlation >= g.summary.median_normal_correlation - 0.02,
        "normal correlation {} vs {}",
        r.summary.median_normal_correlation,
        g.summary.median_normal_correlation
    );
    std::fs::remove_dir_all(&out).ok();
}
