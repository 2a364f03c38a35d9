//! A virtual population on both cores: 100 samples of an atlas of the 30 first femurs of
//! `$ATLASMESH_DATA/knee-distal-femur-synthetic-3d` (hexahedra at 2 % of the mean's largest
//! side, about 2 mm; weights within 3 σ), each sample's surface, FE mesh (morphed, repaired,
//! checked, written as VTU) and picture written, with `instances.json` and `instances.html`,
//! as `atlasmesh sample --n 100 --max-sd 3` does. Without the data, 30 seeded synthetic
//! surfaces of the 3D demo stand in.
//!
//! Budget: about 4 minutes of wall time on 2 cores (`cargo bench -p atlasmesh-bench --bench sample`;
//! docs/benchmarks.md lists every bench's).

use atlasmesh::model::{Atlas, AtlasParams};
use atlasmesh::study::{RunContext, RunParams, RunPlace, sample_specs, write_instances};
use criterion::{Criterion, criterion_group, criterion_main};

fn population() -> (Vec<atlasmesh::geometry::Shape<3>>, &'static str) {
    if let Some(d) = std::env::var_os("ATLASMESH_DATA") {
        let dir = std::path::Path::new(&d).join("knee-distal-femur-synthetic-3d/femur");
        let paths: Vec<_> = (1..=30)
            .map(|k| dir.join(format!("S{k:03}_Femur.ply")))
            .collect();
        return (
            atlasmesh::study::load_surfaces(&paths, &Default::default()).expect("femur data"),
            "femurs",
        );
    }
    (
        atlasmesh::study::demo_population_3d(30, 60, 3).expect("synthetic"),
        "synthetic",
    )
}

fn bench(c: &mut Criterion) {
    faer::set_global_parallelism(faer::Par::Seq);
    let (shapes, label) = population();
    let atlas = Atlas::build(
        &shapes,
        &AtlasParams {
            element_size: 0.02,
            ..AtlasParams::default()
        },
    )
    .expect("atlas");
    let specs = sample_specs(&atlas, 100, 7, Some(3.0)).expect("samples");
    let mut ctx = RunContext::new(atlas, RunParams::default(), RunPlace::default()).expect("run");
    // The morph factorized once, outside the timing, as a run does before its items.
    ctx.morpher().expect("morpher");
    let tmp = tempfile::Builder::new()
        .prefix("atlasmesh-bench-sample-")
        .tempdir()
        .expect("temp folder");
    let dir = tmp.path();
    let mut g = c.benchmark_group("sample");
    g.sample_size(10);
    // Ten samples of as few iterations as fill the measurement time (one, for the slow ones):
    // the budget holds whatever the machine.
    g.sampling_mode(criterion::SamplingMode::Flat);
    let mut run = 0;
    g.bench_function(format!("sample_100_{label}_2_cores"), |b| {
        b.iter(|| {
            run += 1;
            let out = dir.join(format!("out{run}"));
            ctx.place.out = out.clone();
            let r =
                write_instances(&ctx, &specs, None, &atlasmesh::study::Silent).expect("samples");
            assert_eq!(r.summary.written, 100);
            let _ = std::fs::remove_dir_all(&out);
            r.summary.written
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
