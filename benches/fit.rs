//! Benchmarks on the hands: one hand fit (2001 points, 11 modes) on one core, and the whole
//! 40-hand leave-one-out. Reads `$ATLASMESH_DATA/imm-hands-2d`; without it, a seeded
//! synthetic population of the same size stands in.
//!
//! Budget: about 3 minutes of wall time on 2 cores (`cargo bench -p atlasmesh-bench --bench fit`;
//! docs/benchmarks.md lists every bench's).

use atlasmesh::fit::{FitParams, Fitter};
use atlasmesh::geometry::{ClosestPointIndex, Shape};
use atlasmesh::model::{Atlas, AtlasParams, ModeSelection};
use atlasmesh::register::resample_corresponding;
use atlasmesh::study::{
    PopulationOptions, RunParams, demo_population, leave_one_out, load_population,
};
use criterion::{Criterion, criterion_group, criterion_main};

fn hands() -> (Vec<Shape<2>>, bool) {
    if let Some(d) = std::env::var_os("ATLASMESH_DATA") {
        let p = std::path::Path::new(&d).join("imm-hands-2d/hands_long.csv");
        let s = load_population(
            &[p],
            &PopulationOptions {
                closed: false,
                resample: Some(2001),
                ..Default::default()
            },
        )
        .expect("hands data");
        return (s, true);
    }
    let pop = demo_population(40, 56, 7);
    (
        resample_corresponding(&pop, 2001, true)
            .expect("synthetic")
            .0,
        false,
    )
}

fn bench(c: &mut Criterion) {
    faer::set_global_parallelism(faer::Par::Seq);
    let (shapes, real) = hands();
    let label = if real { "imm-hands" } else { "synthetic" };
    let params = AtlasParams {
        modes: ModeSelection::Count(11),
        ..AtlasParams::default()
    };
    // Subject 0, fitted with the atlas of the other 39 (one leave-one-out fold).
    let atlas = Atlas::build(&shapes[1..], &params).expect("atlas");
    let fitter = Fitter::new(std::sync::Arc::new(atlas.clone()));
    let subject = &shapes[0];
    let index = ClosestPointIndex::from_shape(subject);
    let mut g = c.benchmark_group("hands");
    g.sample_size(10);
    // Ten samples of as few iterations as fill the measurement time (one, for the slow ones):
    // the budget holds whatever the machine.
    g.sampling_mode(criterion::SamplingMode::Flat);
    g.bench_function(format!("hand_fit_2001pts_11modes_{label}"), |b| {
        b.iter(|| {
            fitter
                .fit(subject, &index, &FitParams::default())
                .expect("fit")
        })
    });
    // The paper's S38 (index 37): the outlier its Algorithm 1 failed on.
    let atlas37 = Atlas::build(
        &shapes
            .iter()
            .enumerate()
            .filter(|(i, _)| *i != 37)
            .map(|(_, s)| s.clone())
            .collect::<Vec<_>>(),
        &params,
    )
    .expect("atlas");
    let fitter37 = Fitter::new(std::sync::Arc::new(atlas37.clone()));
    let index37 = ClosestPointIndex::from_shape(&shapes[37]);
    g.bench_function(format!("hand_fit_outlier_37_{label}"), |b| {
        b.iter(|| {
            fitter37
                .fit(&shapes[37], &index37, &FitParams::default())
                .expect("fit")
        })
    });
    g.bench_function(format!("hand_fit_one_way_one_start_{label}"), |b| {
        b.iter(|| {
            fitter
                .fit(
                    subject,
                    &index,
                    &FitParams {
                        symmetric: false,
                        starts: 1,
                        full_starts: 1,
                        ..FitParams::default()
                    },
                )
                .expect("fit")
        })
    });
    let run = RunParams {
        atlas: params,
        plots: false,
        ..RunParams::default()
    };
    let tmp = tempfile::Builder::new()
        .prefix("atlasmesh-bench-loo-")
        .tempdir()
        .expect("temporary folder");
    let out = tmp.path().to_path_buf();
    g.sample_size(10);
    g.sampling_mode(criterion::SamplingMode::Flat);
    g.measurement_time(std::time::Duration::from_secs(60));
    g.bench_function(format!("hands_loo_40_{label}"), |b| {
        b.iter(|| {
            leave_one_out(&shapes, label, &run, &out, 0, &atlasmesh::study::Silent).expect("loo")
        })
    });
    g.finish();
}

criterion_group! {
    name = benches;
    // Criterion's HTML plots need system fonts that a bare machine lacks; the figures are
    // in its terminal output and `target/criterion/*/new/estimates.json`.
    config = Criterion::default().without_plots();
    targets = bench
}
criterion_main!(benches);
