//! The atlas of the 10 real VerSe L1 vertebrae (`$ATLASMESH_DATA/verse-L1-vertebrae-3d`), as
//! `atlasmesh build --register --landmarks` makes it: the surfaces read and their islands
//! dropped, the automatic template registered to the other nine (10 landmarks each), GPA,
//! PCA and the hexahedral mesh of the mean at the automatic element size, the atlas file
//! written. On both cores, as a user runs it. Skipped without the data.
//!
//! Budget: about 6 minutes of wall time on 2 cores (`cargo bench -p atlasmesh-bench --bench vertebrae`;
//! docs/benchmarks.md lists every bench's).

use atlasmesh::study::{
    ISLAND_SHARE, RunParams, Silent, Template, attach_landmarks, build, clean_shapes,
    load_surfaces, register_population,
};
use criterion::{Criterion, criterion_group, criterion_main};
use std::path::PathBuf;

fn bench(c: &mut Criterion) {
    let Some(data) = std::env::var_os("ATLASMESH_DATA") else {
        eprintln!("ATLASMESH_DATA is not set: the vertebra benchmark is skipped");
        return;
    };
    let raw = PathBuf::from(data).join("verse-L1-vertebrae-3d/raw");
    let mut surfaces: Vec<PathBuf> = std::fs::read_dir(&raw)
        .expect("vertebra data")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "ply"))
        .collect();
    surfaces.sort();
    let landmarks: Vec<PathBuf> = surfaces.iter().map(|p| p.with_extension("json")).collect();
    let tmp = tempfile::Builder::new()
        .prefix("atlasmesh-bench-vertebrae-")
        .tempdir()
        .expect("temporary folder");
    let out = tmp.path();
    let params = RunParams::default();
    let register = atlasmesh::register::RegisterParams::for_dimension(3);
    let mut g = c.benchmark_group("vertebrae");
    g.sample_size(10);
    // Ten samples of as few iterations as fill the measurement time (one, for the slow ones):
    // the budget holds whatever the machine.
    g.sampling_mode(criterion::SamplingMode::Flat);
    g.bench_function("vertebra_atlas_build_register_10_shapes", |b| {
        b.iter(|| {
            let mut shapes = load_surfaces(&surfaces, &Default::default()).expect("surfaces");
            attach_landmarks(&mut shapes, &landmarks).expect("landmarks");
            clean_shapes(&mut shapes, ISLAND_SHARE);
            let r = register_population(&shapes, Template::Nearest, &register, 0, &Silent)
                .expect("registration");
            build(&r.shapes, &params, &out.join("vertebrae.safetensors")).expect("atlas")
        })
    });
    g.finish();
}

criterion_group! {
    name = benches;
    // As the other benches: the figures are in the terminal and `target/criterion`.
    config = Criterion::default().without_plots();
    targets = bench
}
criterion_main!(benches);
