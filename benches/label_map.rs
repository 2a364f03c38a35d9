//! A label map as TotalSegmentator writes one for an abdominal CT: 384 × 384 × 160 voxels of
//! 1 × 1 × 1.5 mm (uint8, gzip NIfTI), a large organ (label 5, an ellipsoid of ~1.4 M voxels)
//! and a vertebra-sized ring (label 31, a torus of ~60 k voxels). Measured: the file read and
//! label 31's surface extracted (`study::read_label_surface`: mask, largest component,
//! cavities, marching tetrahedra, edge collapse, smoothing; sequential: one core), as
//! `atlasmesh convert seg.nii.gz l1.ply --label 31` does. The file is written once to
//! `target/label_map_bench.nii.gz` (for measuring memory with `/usr/bin/time -v`).
//!
//! Budget: about 1 minutes of wall time on 2 cores (`cargo bench -p atlasmesh-bench --bench label_map`;
//! docs/benchmarks.md lists every bench's).

use criterion::{Criterion, criterion_group, criterion_main};
use std::io::Write;

const DIMS: [usize; 3] = [384, 384, 160];

fn label_map() -> Vec<u8> {
    let [nx, ny, nz] = DIMS;
    let mut v = vec![0u8; nx * ny * nz];
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                let (px, py, pz) = (x as f64, y as f64, z as f64 * 1.5);
                let organ = ((px - 120.0) / 90.0).powi(2)
                    + ((py - 200.0) / 70.0).powi(2)
                    + ((pz - 120.0) / 60.0).powi(2);
                let (cx, cy, cz) = (px - 250.0, py - 250.0, pz - 110.0);
                let ring = ((cx * cx + cy * cy).sqrt() - 22.0).powi(2) + cz * cz;
                v[x + nx * (y + ny * z)] = if ring < 12.0 * 12.0 {
                    31
                } else if organ < 1.0 {
                    5
                } else {
                    0
                };
            }
        }
    }
    v
}

fn nifti_gz(data: &[u8]) -> Vec<u8> {
    let mut h = vec![0u8; 352];
    h[0..4].copy_from_slice(&348i32.to_le_bytes());
    let dim = [
        3i16,
        DIMS[0] as i16,
        DIMS[1] as i16,
        DIMS[2] as i16,
        1,
        1,
        1,
        1,
    ];
    for (k, d) in dim.iter().enumerate() {
        h[40 + 2 * k..42 + 2 * k].copy_from_slice(&d.to_le_bytes());
    }
    h[70..72].copy_from_slice(&2i16.to_le_bytes());
    h[72..74].copy_from_slice(&8i16.to_le_bytes());
    for (k, v) in [1.0f32, 1.0, 1.0, 1.5].iter().enumerate() {
        h[76 + 4 * k..80 + 4 * k].copy_from_slice(&v.to_le_bytes());
    }
    h[108..112].copy_from_slice(&352f32.to_le_bytes());
    h[254..256].copy_from_slice(&1i16.to_le_bytes());
    for (r, s) in [1.0f32, 1.0, 1.5].iter().enumerate() {
        let at = 280 + 16 * r + 4 * r;
        h[at..at + 4].copy_from_slice(&s.to_le_bytes());
    }
    h[344..348].copy_from_slice(b"n+1\0");
    h.extend_from_slice(data);
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    e.write_all(&h).expect("gzip");
    e.finish().expect("gzip")
}

fn bench(c: &mut Criterion) {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/label_map_bench.nii.gz");
    if !path.exists() {
        std::fs::write(&path, nifti_gz(&label_map())).expect("bench file");
    }
    let reading = atlasmesh::study::LabelReading {
        choice: Some("31".parse().expect("label")),
        ..Default::default()
    };
    let s = atlasmesh::study::read_label_surface(&path, &reading).expect("surface");
    eprintln!(
        "label_map: {} voxels of label 31, surface of {} points",
        s.voxels,
        s.shape.points.len()
    );
    let mut g = c.benchmark_group("label_map");
    g.sample_size(10);
    // Ten samples of as few iterations as fill the measurement time (one, for the slow ones):
    // the budget holds whatever the machine.
    g.sampling_mode(criterion::SamplingMode::Flat);
    g.bench_function("read 384x384x160 and extract label 31 (one core)", |b| {
        b.iter(|| atlasmesh::study::read_label_surface(&path, &reading).expect("surface"))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
