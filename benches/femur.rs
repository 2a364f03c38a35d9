//! Benchmarks on the distal femurs (`$ATLASMESH_DATA/knee-distal-femur-synthetic-3d`):
//! one femur fit (7313 vertices, 15 modes) on one core, a whole subject (fit, morph, repair,
//! measures), the hexahedral mesh of the mean femur
//! at 2 mm, the morph plus corner Jacobians of that mesh, and the registration of a femur
//! pair, and the atlas from the 30 femurs made non-corresponding (decimated and
//! shuffled as in `tests/it/register.rs`; registration with 3 landmarks on both cores, then
//! GPA, PCA and the hexahedral mesh of the mean), the morph plus Jacobians of a mesh of the
//! mean with about 100k hexahedra, the cut of a femur by a plane (capped), and the repair of
//! the 2 mm mesh with 1 % of its elements spoiled. Without the data, seeded synthetic surfaces of the 3D demo (7322 vertices) stand
//! in.
//!
//! Budget: about 10 minutes of wall time on 2 cores (`cargo bench -p atlasmesh-bench --bench femur`;
//! docs/benchmarks.md lists every bench's).

#[path = "../tests/it/raw_femurs.rs"]
mod raw_femurs;

use atlasmesh::ffd::FfdParams;
use atlasmesh::fit::{FitParams, Fitter};
use atlasmesh::geometry::ClosestPointIndex;
use atlasmesh::mesh::hex_mesh::{HexMeshParams, hex_mesh};
use atlasmesh::mesh::quality::{mesh_quality, summarize};
use atlasmesh::model::{Atlas, AtlasParams, ModeSelection};
use atlasmesh::study::load_surfaces;
use criterion::{Criterion, criterion_group, criterion_main};

fn bench(c: &mut Criterion) {
    faer::set_global_parallelism(faer::Par::Seq);
    let shapes = match std::env::var_os("ATLASMESH_DATA") {
        Some(d) => {
            let dir = std::path::Path::new(&d).join("knee-distal-femur-synthetic-3d/femur");
            let paths: Vec<_> = (1..=30)
                .map(|k| dir.join(format!("S{k:03}_Femur.ply")))
                .collect();
            load_surfaces(&paths, &Default::default()).expect("femur data")
        }
        None => {
            // 7322 vertices, about the femurs' 7313 (and above their landmark indices).
            eprintln!("ATLASMESH_DATA is not set: synthetic surfaces stand in for the femurs");
            atlasmesh::study::demo_population_3d(30, 61, 5).expect("synthetic")
        }
    };
    let params = AtlasParams {
        modes: ModeSelection::Count(15),
        element_size: 0.02,
        ..AtlasParams::default()
    };
    // S001, fitted with the atlas of the other 29 (one leave-one-out fold).
    let atlas = Atlas::build(&shapes[1..], &params).expect("atlas");
    let fitter = Fitter::new(std::sync::Arc::new(atlas.clone()));
    let subject = &shapes[0];
    let index = ClosestPointIndex::from_shape(subject);
    let mut g = c.benchmark_group("femur");
    g.sample_size(10);
    // Ten samples of as few iterations as fill the measurement time (one, for the slow ones):
    // the budget holds whatever the machine.
    g.sampling_mode(criterion::SamplingMode::Flat);
    g.bench_function("femur_fit_7313pts_15modes", |b| {
        b.iter(|| {
            fitter
                .fit(subject, &index, &FitParams::default())
                .expect("fit")
        })
    });
    // The mean in the reference frame has largest side 1; 2 mm on this femur:
    let (lo, hi) = atlasmesh::geometry::bounding_box(&subject.points);
    let mm = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
    let size = 2.0 / mm;
    let mean = atlas.mean_shape();
    g.bench_function("hex_mesh_mean_femur_2mm", |b| {
        b.iter(|| {
            hex_mesh(
                &mean,
                &HexMeshParams {
                    element_size: size,
                    smoothing_passes: 8,
                },
            )
            .expect("hex mesh")
        })
    });
    let fit = fitter
        .fit(subject, &index, &FitParams::default())
        .expect("fit");
    let morpher = atlas.morpher(&FfdParams::default()).expect("morpher");
    g.bench_function("femur_morph_and_jacobians", |b| {
        b.iter(|| {
            let m = morpher.morph(&fit.correspondence()).expect("morph");
            summarize(&mesh_quality(&m.mesh))
        })
    });
    // The whole subject as `atlasmesh fit` and Python's `Atlas.fit` make it: its index, the
    // fit, the morph, the repair and the measures (`study::fit_subject`), with the fitter made
    // for it as Python makes one per call.
    let run = atlasmesh::study::RunParams {
        plots: false,
        ..Default::default()
    };
    g.bench_function("femur_subject_fit_morph_repair", |b| {
        b.iter(|| {
            let fitter = Fitter::new(std::sync::Arc::new(atlas.clone()));
            atlasmesh::study::fit_subject(&atlas, &fitter, &morpher, subject, &run)
                .expect("subject")
        })
    });
    // Morph plus Jacobians of a 100k-hexahedron mesh of the mean (about 1.27 mm).
    let mut fine = atlas.clone();
    fine.mesh = hex_mesh(
        &mean,
        &HexMeshParams {
            element_size: size * 0.635,
            smoothing_passes: 8,
        },
    )
    .expect("hex mesh")
    .mesh;
    eprintln!("fine mesh: {} hexahedra", fine.mesh.num_elements());
    let fine_morpher = fine.morpher(&FfdParams::default()).expect("morpher");
    g.bench_function("morph_and_jacobians_100k_hex", |b| {
        b.iter(|| {
            let m = fine_morpher.morph(&fit.correspondence()).expect("morph");
            summarize(&mesh_quality(&m.mesh))
        })
    });
    // The common cut of one femur (what `--cut` does to each shape of `build` and `loo`, and
    // `fit` to a subject reaching beyond an atlas's cut): the plane 20 mm below the top, the
    // part beyond removed, the section capped (constrained Delaunay), and the trimmed shape's
    // closest-point index.
    g.bench_function("femur_cut_by_plane", |b| {
        let top = hi[2];
        let plane = atlasmesh::geometry::Plane {
            point: [0.0, 0.0, top - 20.0],
            normal: [0.0, 0.0, 1.0],
        };
        b.iter(|| {
            let cut = atlasmesh::geometry::cut_by_plane(subject, &plane).expect("cut");
            ClosestPointIndex::from_shape(&cut.shape)
        })
    });
    // Registration of one femur pair (7313 vertices each, no landmarks): S001 to S002.
    g.bench_function("femur_pair_registration", |b| {
        let index = ClosestPointIndex::from_shape(&shapes[1]);
        b.iter(|| {
            atlasmesh::register::register(
                &shapes[0],
                &shapes[1],
                &index,
                &atlasmesh::register::RegisterParams::for_dimension(3),
            )
            .expect("registration")
        })
    });
    g.finish();
    // Repair: the mean femur's hex mesh at 2 mm with about 1 % of its elements
    // spoiled (interior nodes pushed by 0.8 of an edge, seeded), repaired on one core.
    let mesh = hex_mesh(
        &mean,
        &HexMeshParams {
            element_size: size,
            smoothing_passes: 8,
        },
    )
    .expect("hex mesh")
    .mesh;
    let boundary: std::collections::HashSet<usize> = atlasmesh::mesh::boundary_faces(&mesh)
        .iter()
        .flat_map(|f| f.nodes.clone())
        .collect();
    let mut spoiled = mesh.clone();
    let h = size;
    let mut k = 0u64;
    let target = mesh.num_elements() / 100;
    let mut i = 0;
    while summarize_below(&spoiled) < target && i < spoiled.nodes.len() {
        if !boundary.contains(&i) {
            k = k
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let a = (k >> 33) as f64 / (1u64 << 31) as f64 * std::f64::consts::TAU;
            spoiled.nodes[i][0] += 0.8 * h * a.cos();
            spoiled.nodes[i][1] += 0.8 * h * a.sin();
        }
        i += 37;
    }
    eprintln!(
        "repair bench: {} hexahedra, {} below 0.2 after spoiling",
        spoiled.num_elements(),
        summarize_below(&spoiled)
    );
    let mut g = c.benchmark_group("repair");
    g.sample_size(10);
    g.sampling_mode(criterion::SamplingMode::Flat);
    g.bench_function("repair_femur_hex_1pct", |b| {
        b.iter(|| {
            let mut m = spoiled.clone();
            atlasmesh::mesh::repair::repair(&mut m, None, &Default::default()).expect("repair")
        })
    });
    g.finish();
    let (raw, _) = raw_femurs::raw_femurs(&shapes, 30);
    let mut g = c.benchmark_group("raw_femurs");
    g.sample_size(10);
    g.sampling_mode(criterion::SamplingMode::Flat);
    g.bench_function("atlas_from_30_raw_femurs_2_cores", |b| {
        b.iter(|| {
            let corresponded = atlasmesh::study::register_population(
                &raw,
                atlasmesh::study::Template::Nearest,
                &atlasmesh::register::RegisterParams::for_dimension(3),
                0,
                &atlasmesh::study::Silent,
            )
            .expect("registration")
            .shapes;
            Atlas::build(&corresponded, &params).expect("atlas")
        })
    });
    g.finish();
}

/// Elements below the hexahedra's repair bound 0.2.
fn summarize_below(m: &atlasmesh::mesh::FeMesh<3>) -> usize {
    mesh_quality(m)
        .iter()
        .filter(|q| q.scaled_jacobian_min < 0.2)
        .count()
}

criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench
}
criterion_main!(benches);
