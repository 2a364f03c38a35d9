//! Materials from a CT at the size of a clinical scan: 60 000 hexahedra (1.5 mm, slightly
//! distorted) mapped on a 512 × 512 × 300 CT of 0.7 × 0.7 × 1 mm (int16 HU, a smooth field
//! with noise), on one core (`map_materials`: V3 integration over every element, binning,
//! checks). The CT's conversion to a field (`CtField::new`) is measured apart.
//!
//! Budget: about 2 minutes of wall time on 2 cores (`cargo bench -p atlasmesh-bench --bench materials`;
//! docs/benchmarks.md lists every bench's).

use atlasmesh::image::{Image, VoxelType, WorldConvention};
use atlasmesh::materials::{CtField, MaterialRecipe, map_materials};
use atlasmesh::mesh::{ElementKind, FeMesh};
use criterion::{Criterion, criterion_group, criterion_main};
use rand::{RngExt, SeedableRng};

const DIMS: [usize; 3] = [512, 512, 300];

fn ct() -> Image {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let [nx, ny, nz] = DIMS;
    let mut data = Vec::with_capacity(nx * ny * nz * 2);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let (x, y, z) = (i as f64 * 0.7, j as f64 * 0.7, k as f64);
                let bone = 400.0 + 300.0 * (x / 17.0).sin() * (y / 23.0).cos() + 2.0 * (z - 150.0);
                let v = bone + rng.random_range(-60.0..60.0);
                data.extend((v as i16).to_le_bytes());
            }
        }
    }
    Image {
        dims: DIMS,
        voxel_type: VoxelType::I16,
        little_endian: true,
        data,
        slope: 1.0,
        intercept: 0.0,
        affine: [
            [0.7, 0.0, 0.0, 0.0],
            [0.0, 0.7, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
        ],
        file_convention: WorldConvention::Ras,
    }
}

/// 40 × 40 × 37.5 hexahedra of 1.5 mm (60 000), nodes jittered by up to 0.2 mm, centred in
/// the CT.
fn mesh() -> FeMesh<3> {
    let (nx, ny, nz) = (40, 40, 38);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2);
    let id = |x: usize, y: usize, z: usize| x + (nx + 1) * (y + (ny + 1) * z);
    let mut nodes = Vec::new();
    for z in 0..=nz {
        for y in 0..=ny {
            for x in 0..=nx {
                let j = |r: &mut rand_chacha::ChaCha8Rng| r.random_range(-0.2..0.2);
                nodes.push([
                    150.0 + 1.5 * x as f64 + j(&mut rng),
                    150.0 + 1.5 * y as f64 + j(&mut rng),
                    120.0 + 1.5 * z as f64 + j(&mut rng),
                ]);
            }
        }
    }
    let mut connectivity = Vec::new();
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                if connectivity.len() / 8 == 60_000 {
                    break;
                }
                connectivity.extend([
                    id(x, y, z),
                    id(x + 1, y, z),
                    id(x + 1, y + 1, z),
                    id(x, y + 1, z),
                    id(x, y, z + 1),
                    id(x + 1, y, z + 1),
                    id(x + 1, y + 1, z + 1),
                    id(x, y + 1, z + 1),
                ]);
            }
        }
    }
    FeMesh {
        nodes,
        kind: ElementKind::Hex8,
        connectivity,
        sets: Default::default(),
    }
}

fn bench(c: &mut Criterion) {
    let image = ct();
    let field = CtField::new(&image).expect("field");
    let mesh = mesh();
    assert_eq!(mesh.num_elements(), 60_000);
    let recipe = MaterialRecipe::default().law().expect("recipe");
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    let mut g = c.benchmark_group("materials");
    g.sample_size(10);
    // Ten samples of as few iterations as fill the measurement time (one, for the slow ones):
    // the budget holds whatever the machine.
    g.sampling_mode(criterion::SamplingMode::Flat);
    g.bench_function("60k_hex8_on_512x512x300_ct_one_core", |b| {
        b.iter(|| one.install(|| map_materials(&mesh, &field, &recipe).expect("map")))
    });
    g.bench_function("ct_field_of_512x512x300_int16", |b| {
        b.iter(|| CtField::new(&image).expect("field"))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
