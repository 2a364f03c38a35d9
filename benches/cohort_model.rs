//! The shape model of a cohort: the in-memory build (GPA, dense thin SVD) against the
//! streamed one (GPA in passes, randomized PCA, `Atlas::build_streamed`), on seeded synthetic
//! 3D shapes of 2 000 points in correspondence (30 deformation modes of decaying size and a
//! random pose each), 50 modes kept.
//!
//! - `cohort/dense_1000x2000` and `cohort/streamed_1000x2000`: the same 1 000 shapes held in
//!   memory, built both ways (the streamed one reading them in batches of 256);
//! - `cohort/streamed_generated_4000x2000`: 4 000 shapes made when a pass reads them (as
//!   files would be read), never held: the memory of a cohort that does not fit.
//!
//! Before the timings, each configuration is built once with the heap counted
//! (`CountingAllocator`) and its peak printed, with the leading eigenvalues' agreement of
//! the streamed and the dense model.
//!
//! Budget: about 4 minutes of wall time on 2 cores (`cargo bench -p atlasmesh-bench --bench
//! cohort_model`; docs/benchmarks.md lists every bench's).

use atlasmesh::geometry::Point;
use atlasmesh::model::{Atlas, AtlasParams, ModeSelection, ShapeSource, StreamParams};
use atlasmesh::study::run::{CountingAllocator, heap_peak_mb, reset_heap_peak};
use criterion::{Criterion, criterion_group, criterion_main};
use rand::{RngExt, SeedableRng};
use std::ops::Range;

#[global_allocator]
static ALLOCATOR: CountingAllocator = CountingAllocator;

const POINTS: usize = 2000;
const MODES: usize = 30;

/// Seeded synthetic shapes, shape `k` made from its own stream: a wobbly ellipsoid's points
/// moved by `MODES` smooth fields (tabulated once) of amplitude `0.8^j` times a normal draw,
/// then posed. Making a shape costs about what reading a small file does (0.1 ms).
struct Generated {
    n: usize,
    seed: u64,
    /// The ellipsoid's points.
    base: Vec<Point<3>>,
    /// `MODES` displacement fields, one vector per point.
    fields: Vec<Vec<Point<3>>>,
}

fn normal(rng: &mut rand_chacha::ChaCha8Rng) -> f64 {
    let u: f64 = rng.random_range(1e-12..1.0);
    let v: f64 = rng.random_range(0.0..1.0);
    (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

impl Generated {
    fn new(n: usize, seed: u64) -> Self {
        // A Fibonacci sphere stretched to an ellipsoid (40 × 25 × 15).
        let unit: Vec<Point<3>> = (0..POINTS)
            .map(|i| {
                let z = 1.0 - 2.0 * (i as f64 + 0.5) / POINTS as f64;
                let r = (1.0 - z * z).sqrt();
                let phi = i as f64 * 2.399_963_229_728_653;
                [r * phi.cos(), r * phi.sin(), z]
            })
            .collect();
        let base = unit
            .iter()
            .map(|p| [40.0 * p[0], 25.0 * p[1], 15.0 * p[2]])
            .collect();
        let fields = (0..MODES)
            .map(|j| {
                let a = 0.8f64.powi(j as i32) * 0.08;
                unit.iter()
                    .map(|p| {
                        let f =
                            ((j % 5 + 1) as f64 * p[0] + (j / 5 + 1) as f64 * p[1] + p[2]).sin();
                        [
                            40.0 * a * f * p[0],
                            25.0 * a * f * p[1],
                            -15.0 * a * f * p[2],
                        ]
                    })
                    .collect()
            })
            .collect();
        Generated {
            n,
            seed,
            base,
            fields,
        }
    }

    fn shape(&self, k: usize) -> Vec<Point<3>> {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(self.seed ^ (k as u64 * 0x9E37));
        let w: Vec<f64> = (0..MODES).map(|_| normal(&mut rng)).collect();
        let axis: [f64; 3] = std::array::from_fn(|_| 0.5 * normal(&mut rng));
        let mut pose = atlasmesh::geometry::Similarity::<3>::identity();
        pose.r = atlasmesh::geometry::rotation_exp::<3>(&axis);
        pose.s = 1.0 + 0.2 * normal(&mut rng).tanh();
        pose.t = std::array::from_fn(|_| 10.0 * normal(&mut rng));
        let mut points = self.base.clone();
        for (wj, field) in w.iter().zip(&self.fields) {
            for (p, f) in points.iter_mut().zip(field) {
                for d in 0..3 {
                    p[d] += wj * f[d];
                }
            }
        }
        points.iter().map(|p| pose.apply(p)).collect()
    }
}

impl ShapeSource<3> for Generated {
    fn len(&self) -> usize {
        self.n
    }

    fn read(&self, range: Range<usize>) -> atlasmesh::Result<Vec<Vec<Point<3>>>> {
        Ok(range.map(|k| self.shape(k)).collect())
    }
}

fn params() -> AtlasParams {
    AtlasParams {
        modes: ModeSelection::Count(50),
        ..AtlasParams::default()
    }
}

fn dense(shapes: &[Vec<Point<3>>]) -> Atlas<3> {
    let shapes: Vec<atlasmesh::geometry::Shape<3>> = shapes
        .iter()
        .enumerate()
        .map(|(k, p)| atlasmesh::geometry::Shape {
            name: format!("s{k}"),
            points: p.clone(),
            facets: Vec::new(),
            landmarks: Vec::new(),
        })
        .collect();
    Atlas::build_model(&shapes, &params()).expect("dense model")
}

fn streamed(source: &dyn ShapeSource<3>) -> Atlas<3> {
    Atlas::build_streamed(
        source,
        Vec::new(),
        Vec::new(),
        &params(),
        &StreamParams::default(),
        |_, _| {
            Ok(atlasmesh::mesh::FeMesh {
                nodes: Vec::new(),
                kind: atlasmesh::mesh::ElementKind::Hex8,
                connectivity: Vec::new(),
                sets: Default::default(),
            })
        },
    )
    .expect("streamed model")
}

/// `f` once with the heap's peak counted above what was in use before: (result, MB).
fn peak<T>(f: impl FnOnce() -> T) -> (T, f64) {
    reset_heap_peak();
    // (Just after the reset, the peak is the heap in use.)
    let before = heap_peak_mb().expect("the heap is counted");
    let t = f();
    (t, heap_peak_mb().expect("the heap is counted") - before)
}

fn bench(c: &mut Criterion) {
    let small = Generated::new(1000, 1);
    let shapes = small.read(0..small.n).expect("shapes");
    let held = (shapes.len() * POINTS * 24) as f64 / 1e6;
    let (d, dense_mb) = peak(|| dense(&shapes));
    let (s, streamed_mb) = peak(|| streamed(&shapes));
    let worst = (0..50)
        .map(|k| (s.eigenvalues[k] / d.eigenvalues[k] - 1.0).abs())
        .fold(0.0, f64::max);
    println!(
        "1000 × 2000 held ({held:.0} MB): dense heap peak {dense_mb:.0} MB above them, streamed \
         {streamed_mb:.0} MB; the 50 eigenvalues agree to {worst:.1e}"
    );
    let large = Generated::new(4000, 2);
    let (_, large_mb) = peak(|| streamed(&large));
    println!(
        "4000 × 2000 generated on each pass ({:.0} MB if held): streamed heap peak {large_mb:.0} MB",
        (large.n * POINTS * 24) as f64 / 1e6
    );
    let mut g = c.benchmark_group("cohort");
    g.sample_size(10);
    g.sampling_mode(criterion::SamplingMode::Flat);
    g.bench_function("dense_1000x2000", |b| {
        b.iter(|| dense(&shapes).eigenvalues[0])
    });
    g.bench_function("streamed_1000x2000", |b| {
        b.iter(|| streamed(&shapes).eigenvalues[0])
    });
    g.bench_function("streamed_generated_4000x2000", |b| {
        b.iter(|| streamed(&large).eigenvalues[0])
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench
}
criterion_main!(benches);
