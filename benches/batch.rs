//! A batch on both cores: 200 femur subjects (the 100 femurs of
//! `$ATLASMESH_DATA/knee-distal-femur-synthetic-3d`, each as given and under a seeded random
//! rigid motion) fitted, morphed, repaired, checked and written (VTU) with an atlas of the
//! 100 (15 modes, hexahedra at 2 % of the mean's largest side, about 2 mm). Without the data,
//! 200 seeded synthetic surfaces of the 3D demo (7200 vertices) stand in. Peak memory is
//! measured outside (`/usr/bin/time -v atlasmesh fit ...`, see the README).
//!
//! Budget: about 8 minutes of wall time on 2 cores (`cargo bench -p atlasmesh-bench --bench batch`;
//! docs/benchmarks.md lists every bench's).

use atlasmesh::geometry::{Shape, Similarity};
use atlasmesh::model::{Atlas, AtlasParams, ModeSelection};
use atlasmesh::study::RunParams;
use atlasmesh::study::batch::fit_batch;
use atlasmesh::study::{RunContext, RunPlace, SubjectReading};
use criterion::{Criterion, criterion_group, criterion_main};
use rand::{RngExt, SeedableRng};

fn population() -> (Vec<Shape<3>>, &'static str) {
    if let Some(d) = std::env::var_os("ATLASMESH_DATA") {
        let dir = std::path::Path::new(&d).join("knee-distal-femur-synthetic-3d/femur");
        let paths: Vec<_> = (1..=100)
            .map(|k| dir.join(format!("S{k:03}_Femur.ply")))
            .collect();
        return (
            atlasmesh::study::load_surfaces(&paths, &Default::default()).expect("femur data"),
            "femurs",
        );
    }
    (
        atlasmesh::study::demo_population_3d(100, 60, 3).expect("synthetic"),
        "synthetic",
    )
}

fn bench(c: &mut Criterion) {
    faer::set_global_parallelism(faer::Par::Seq);
    let (shapes, label) = population();
    let atlas = Atlas::build(
        &shapes,
        &AtlasParams {
            modes: ModeSelection::Count(15),
            element_size: 0.02,
            ..AtlasParams::default()
        },
    )
    .expect("atlas");
    // Removed when the bench ends, or is interrupted by a panic.
    let tmp = tempfile::Builder::new()
        .prefix("atlasmesh-bench-batch-")
        .tempdir()
        .expect("temp folder");
    let dir = tmp.path();
    let subjects = dir.join("subjects");
    std::fs::create_dir_all(&subjects).expect("temp folder");
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let mut files = Vec::new();
    for s in &shapes {
        let w: [f64; 3] = std::array::from_fn(|_| rng.random_range(-1.5..1.5));
        let mut motion = Similarity::<3>::identity();
        motion.r = atlasmesh::geometry::rotation_exp::<3>(&w);
        motion.t = std::array::from_fn(|_| rng.random_range(-100.0..100.0));
        let mut moved = s.clone();
        moved.points.iter_mut().for_each(|p| *p = motion.apply(p));
        for (name, shape) in [(s.name.clone(), s), (format!("{}_moved", s.name), &moved)] {
            let p = subjects.join(format!("{name}.ply"));
            atlasmesh::formats::write_ply(&p, shape).expect("write subject");
            files.push(p);
        }
    }
    let params = RunParams {
        plots: false,
        ..RunParams::default()
    };
    let mut ctx = RunContext::new(atlas, params, RunPlace::default()).expect("run");
    // The fitter and the morph made once, outside the timing, as a run does before its items.
    ctx.fitter().expect("fitter");
    ctx.morpher().expect("morpher");
    let mut g = c.benchmark_group("batch");
    g.sample_size(10);
    // Ten samples of as few iterations as fill the measurement time (one, for the slow ones):
    // the budget holds whatever the machine.
    g.sampling_mode(criterion::SamplingMode::Flat);
    let mut run = 0;
    g.bench_function(format!("batch_200_{label}_2_cores"), |b| {
        b.iter(|| {
            run += 1;
            let out = dir.join(format!("out{run}"));
            ctx.place.out = out.clone();
            let r = fit_batch(
                &ctx,
                &files,
                &SubjectReading::default(),
                label,
                &atlasmesh::study::Silent,
            )
            .expect("batch");
            assert_eq!(r.summary.failed, 0);
            let _ = std::fs::remove_dir_all(&out);
            r.summary.succeeded
        })
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench
}
criterion_main!(benches);
