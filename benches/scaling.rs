//! Scaling of one fit, one core: fit time against the number of vertices and
//! against the number of modes. Two experiments on the femurs of
//! `$ATLASMESH_DATA/knee-distal-femur-synthetic-3d` (subject S001, atlas of S002-S021, 10
//! modes): `femur subject` keeps the atlas as given (7313 points) and varies the subject's
//! size: S001 decimated by vertex clustering (about 1k vertices), as given, and after one and
//! two midpoint subdivisions (29 246 and 116 978, the same surface); `femur` varies atlas and
//! subject together: all 21 femurs decimated alike (the kept vertices and facets of S001's
//! decimation taken on every femur, which keeps the correspondence), as given and subdivided.
//! Besides, the seeded synthetic surfaces of the 3D demo at about 1k, 3k, 10k, 30k and 100k
//! vertices, atlas and subject together (without the data, only these). After the
//! measurements the medians are plotted to `docs/scaling.png` and printed with the fitted
//! exponent of time against vertices.
//!
//! Budget: about 8 minutes of wall time on 2 cores (`cargo bench -p atlasmesh-bench --bench scaling`;
//! docs/benchmarks.md lists every bench's).

use atlasmesh::fit::{FitParams, Fitter};
use atlasmesh::geometry::{ClosestPointIndex, Shape};
use atlasmesh::model::{Atlas, AtlasParams, ModeSelection};
use criterion::measurement::WallTime;
use criterion::{BenchmarkGroup, BenchmarkId, Criterion, criterion_group, criterion_main};
use plotters::prelude::*;
use std::collections::HashMap;

/// Every triangle split into four at its edges' midpoints (same topology on every shape of a
/// population, so vertices keep corresponding).
fn subdivide(s: &Shape<3>) -> Shape<3> {
    let mut points = s.points.clone();
    let mut mid: HashMap<(usize, usize), usize> = HashMap::new();
    let mut at = |a: usize, b: usize, points: &mut Vec<[f64; 3]>| -> usize {
        let key = (a.min(b), a.max(b));
        *mid.entry(key).or_insert_with(|| {
            let (p, q) = (points[a], points[b]);
            points.push(std::array::from_fn(|d| 0.5 * (p[d] + q[d])));
            points.len() - 1
        })
    };
    let mut facets = Vec::with_capacity(4 * s.facets.len());
    for f in &s.facets {
        let ab = at(f[0], f[1], &mut points);
        let bc = at(f[1], f[2], &mut points);
        let ca = at(f[2], f[0], &mut points);
        facets.extend([[f[0], ab, ca], [ab, f[1], bc], [ca, bc, f[2]], [ab, bc, ca]]);
    }
    Shape {
        name: s.name.clone(),
        points,
        facets,
        landmarks: Vec::new(),
    }
}

/// `shape` decimated by vertex clustering to about `target` vertices, and the indices of the
/// kept vertices.
fn decimate(shape: &Shape<3>, target: usize) -> (Shape<3>, Vec<usize>) {
    let (lo, hi) = atlasmesh::geometry::bounding_box(&shape.points);
    let mut cell = (0..3).map(|d| hi[d] - lo[d]).fold(0.0, f64::max) / (target as f64).sqrt();
    loop {
        let (small, ids) = shape
            .decimate_by_clustering(cell, [0.0; 3])
            .expect("decimation");
        let got = small.points.len();
        if got.abs_diff(target) * 10 <= target {
            return (small, ids);
        }
        cell *= (got as f64 / target as f64).sqrt();
    }
}

/// The femurs S001-S021 as given.
fn femurs() -> Option<Vec<Shape<3>>> {
    let Some(d) = std::env::var_os("ATLASMESH_DATA") else {
        eprintln!("femur scaling skipped: ATLASMESH_DATA is not set");
        return None;
    };
    let dir = std::path::Path::new(&d).join("knee-distal-femur-synthetic-3d/femur");
    let paths: Vec<_> = (1..=21)
        .map(|k| dir.join(format!("S{k:03}_Femur.ply")))
        .collect();
    Some(atlasmesh::study::load_surfaces(&paths, &Default::default()).expect("femur data"))
}

/// (family, shapes) at each size, atlas and subject together; `femurs` as given.
fn populations(femurs: Option<&[Shape<3>]>) -> Vec<(&'static str, Vec<Shape<3>>)> {
    let mut out = Vec::new();
    for rings in [22, 39, 71, 122, 224] {
        let shapes = atlasmesh::study::demo_population_3d(21, rings, 11).expect("synthetic");
        out.push(("synthetic", shapes));
    }
    if let Some(femurs) = femurs {
        let mut shapes = femurs.to_vec();
        let (small, ids) = decimate(&shapes[0], 1800);
        let decimated = shapes
            .iter()
            .map(|s| Shape {
                name: s.name.clone(),
                points: ids.iter().map(|&i| s.points[i]).collect(),
                facets: small.facets.clone(),
                landmarks: Vec::new(),
            })
            .collect();
        out.push(("femur", decimated));
        for _ in 0..3 {
            out.push(("femur", shapes.clone()));
            shapes = shapes.iter().map(subdivide).collect();
        }
    }
    out
}

/// The subject S001 at each size, for the atlas of the others (`femurs` as given).
fn subjects(shapes: &[Shape<3>]) -> (Vec<Shape<3>>, Vec<Shape<3>>) {
    let mut subjects = vec![decimate(&shapes[0], 1000).0, shapes[0].clone()];
    for _ in 0..2 {
        let finer = subdivide(&subjects[subjects.len() - 1]);
        subjects.push(finer);
    }
    (shapes[1..].to_vec(), subjects)
}

/// The atlas of `shapes` with `modes` modes.
fn atlas_of(shapes: &[Shape<3>], modes: usize) -> Atlas<3> {
    Atlas::build(
        shapes,
        &AtlasParams {
            modes: ModeSelection::Count(modes),
            element_size: 0.1,
            ..AtlasParams::default()
        },
    )
    .expect("atlas")
}

/// Benchmarks the fit of `subject`, under `family` and its vertex count (noted in `sizes`).
fn bench_fit(
    g: &mut BenchmarkGroup<WallTime>,
    sizes: &mut Vec<(&'static str, usize)>,
    family: &'static str,
    fitter: &Fitter<3>,
    subject: &Shape<3>,
) {
    let index = ClosestPointIndex::from_shape(subject);
    let n = subject.points.len();
    sizes.push((family, n));
    g.bench_with_input(BenchmarkId::new(family, n), &n, |b, _| {
        b.iter(|| {
            fitter
                .fit(subject, &index, &FitParams::default())
                .expect("fit")
        })
    });
}

fn bench(c: &mut Criterion) {
    faer::set_global_parallelism(faer::Par::Seq);
    let mut g = c.benchmark_group("scaling_vertices");
    g.sample_size(10);
    // Ten samples of as few iterations as fill the measurement time (one, for the slow ones):
    // the budget holds whatever the machine.
    g.sampling_mode(criterion::SamplingMode::Flat);
    let mut sizes: Vec<(&str, usize)> = Vec::new();
    let femurs = femurs();
    let populations = populations(femurs.as_deref());
    for (family, shapes) in &populations {
        // Subject 0 fitted with the atlas of the other 20, 10 modes.
        let atlas = atlas_of(&shapes[1..], 10);
        bench_fit(
            &mut g,
            &mut sizes,
            family,
            &Fitter::new(std::sync::Arc::new(atlas.clone())),
            &shapes[0],
        );
    }
    // The subject alone.
    if let Some((training, subjects)) = femurs.as_deref().map(subjects) {
        let atlas = atlas_of(&training, 10);
        let fitter = Fitter::new(std::sync::Arc::new(atlas.clone()));
        for subject in &subjects {
            bench_fit(&mut g, &mut sizes, "femur subject", &fitter, subject);
        }
    }
    g.finish();
    // Modes: the synthetic 10k family has 4 true modes; the femurs (when there) have more.
    let mut g = c.benchmark_group("scaling_modes");
    g.sample_size(10);
    g.sampling_mode(criterion::SamplingMode::Flat);
    let fallback;
    let (family, shapes): (&str, &[Shape<3>]) = match populations
        .iter()
        .rfind(|(f, s)| *f == "femur" && s[0].points.len() < 10_000)
    {
        Some((f, s)) => (f, s),
        None => {
            fallback = atlasmesh::study::demo_population_3d(31, 71, 11).expect("synthetic");
            ("synthetic", &fallback)
        }
    };
    let modes: Vec<usize> = vec![1, 5, 10, 15, 20, 25];
    let mut measured_modes = Vec::new();
    for &m in &modes {
        if m >= shapes.len() - 1 {
            continue;
        }
        let atlas = atlas_of(&shapes[1..], m);
        let fitter = Fitter::new(std::sync::Arc::new(atlas.clone()));
        let index = ClosestPointIndex::from_shape(&shapes[0]);
        measured_modes.push(m);
        g.bench_with_input(BenchmarkId::new(family, m), &m, |b, _| {
            b.iter(|| {
                fitter
                    .fit(&shapes[0], &index, &FitParams::default())
                    .expect("fit")
            })
        });
    }
    g.finish();
    plot(&sizes, family, &measured_modes);
}

/// The median of a criterion measurement (seconds), from its estimates file.
fn median(group: &str, family: &str, x: usize) -> Option<f64> {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("target/criterion")
        .join(group)
        .join(family)
        .join(x.to_string())
        .join("new/estimates.json");
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(p).ok()?).ok()?;
    v["median"]["point_estimate"].as_f64().map(|ns| ns * 1e-9)
}

fn plot(sizes: &[(&str, usize)], mode_family: &str, modes: &[usize]) {
    let mut series: Vec<(&str, Vec<(f64, f64)>)> = Vec::new();
    for family in ["synthetic", "femur", "femur subject"] {
        let pts: Vec<(f64, f64)> = sizes
            .iter()
            .filter(|(f, _)| *f == family)
            .filter_map(|&(f, n)| median("scaling_vertices", f, n).map(|t| (n as f64, t)))
            .collect();
        if pts.len() >= 2 {
            // Least-squares slope of log t against log n.
            let k = pts.len() as f64;
            let (sx, sy) = pts
                .iter()
                .fold((0.0, 0.0), |a, p| (a.0 + p.0.ln(), a.1 + p.1.ln()));
            let (mx, my) = (sx / k, sy / k);
            let (sxy, sxx) = pts.iter().fold((0.0, 0.0), |a, p| {
                (
                    a.0 + (p.0.ln() - mx) * (p.1.ln() - my),
                    a.1 + (p.0.ln() - mx).powi(2),
                )
            });
            eprintln!(
                "{family}: fit time ~ vertices^{:.2} ({})",
                sxy / sxx,
                pts.iter()
                    .map(|p| format!("{:.0}: {:.1} ms", p.0, p.1 * 1e3))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
            for w in pts.windows(2) {
                let ((n0, t0), (n1, t1)) = (w[0], w[1]);
                eprintln!(
                    "  {n0:.0} -> {n1:.0} vertices: time x{:.2}, N log N x{:.2}",
                    t1 / t0,
                    n1 * n1.ln() / (n0 * n0.ln())
                );
            }
            series.push((family, pts));
        }
    }
    let by_modes: Vec<(f64, f64)> = modes
        .iter()
        .filter_map(|&m| median("scaling_modes", mode_family, m).map(|t| (m as f64, t)))
        .collect();
    eprintln!(
        "{mode_family}: fit time by modes: {}",
        by_modes
            .iter()
            .map(|p| format!("{}: {:.1} ms", p.0, p.1 * 1e3))
            .collect::<Vec<_>>()
            .join(", ")
    );
    if series.is_empty() {
        return;
    }
    if !atlasmesh::report::font_available() {
        eprintln!("no font for the plot's labels; plot skipped");
        return;
    }
    let out = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/scaling.png");
    let _ = std::fs::create_dir_all(out.parent().unwrap_or(std::path::Path::new(".")));
    let root = BitMapBackend::new(&out, (1100, 440)).into_drawing_area();
    let _ = root.fill(&WHITE);
    let (left, right) = root.split_horizontally(600);
    let all: Vec<&(f64, f64)> = series.iter().flat_map(|s| s.1.iter()).collect();
    let (x0, x1) = (
        all.iter().map(|p| p.0).fold(f64::INFINITY, f64::min) * 0.8,
        all.iter().map(|p| p.0).fold(0.0, f64::max) * 1.25,
    );
    let (y0, y1) = (
        all.iter().map(|p| p.1).fold(f64::INFINITY, f64::min) * 0.5,
        // Room for the N log N references too.
        series
            .iter()
            .filter_map(|(_, pts)| {
                let &(n0, t0) = pts.first()?;
                let n1 = pts.iter().map(|p| p.0).fold(n0, f64::max);
                Some(t0 * n1 * n1.ln() / (n0 * n0.ln()))
            })
            .chain(all.iter().map(|p| p.1))
            .fold(0.0, f64::max)
            * 1.5,
    );
    if let Ok(mut chart) = ChartBuilder::on(&left)
        .caption("fit time against vertices (one core)", ("sans-serif", 18))
        .margin(10)
        .x_label_area_size(36)
        .y_label_area_size(56)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
    {
        let _ = chart
            .configure_mesh()
            .x_desc("vertices of the subject")
            .y_desc("seconds")
            .draw();
        for (k, (family, pts)) in series.iter().enumerate() {
            let color = [
                RGBColor(200, 30, 60),
                RGBColor(30, 150, 60),
                RGBColor(30, 90, 200),
            ][k % 3]
                .to_rgba();
            let _ = chart
                .draw_series(LineSeries::new(pts.iter().copied(), color.stroke_width(2)))
                .map(|s| {
                    let label = match *family {
                        "femur" => "femur (atlas and subject)",
                        "femur subject" => "femur subject (atlas of 7313 points)",
                        other => other,
                    };
                    s.label(label).legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 16, y)], color.stroke_width(2))
                    })
                });
            let _ = chart.draw_series(pts.iter().map(|&p| Circle::new(p, 4, color.filled())));
        }
        // N log N through the first point of each series.
        for (k, (_, pts)) in series.iter().enumerate() {
            let Some(&(n0, t0)) = pts.first() else {
                continue;
            };
            let n1 = pts.iter().map(|p| p.0).fold(n0, f64::max);
            let reference: Vec<(f64, f64)> = (0..=20)
                .map(|i| {
                    let n = n0 * (n1 / n0).powf(i as f64 / 20.0);
                    (n, t0 * n * n.ln() / (n0 * n0.ln()))
                })
                .collect();
            let style = BLACK.mix(0.35);
            let drawn = chart.draw_series(DashedLineSeries::new(reference, 4, 4, style.into()));
            if k == 0 {
                let _ = drawn.map(|s| {
                    s.label("N log N (from each first point)")
                        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], style))
                });
            }
        }
        let _ = chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw();
    }
    if !by_modes.is_empty() {
        let ymax = by_modes.iter().map(|p| p.1).fold(0.0, f64::max) * 1.2;
        let xmax = by_modes.iter().map(|p| p.0).fold(0.0, f64::max) + 1.0;
        if let Ok(mut chart) = ChartBuilder::on(&right)
            .caption(
                format!("fit time against modes ({mode_family})"),
                ("sans-serif", 18),
            )
            .margin(10)
            .x_label_area_size(36)
            .y_label_area_size(56)
            .build_cartesian_2d(0.0..xmax, 0.0..ymax)
        {
            let _ = chart
                .configure_mesh()
                .x_desc("modes")
                .y_desc("seconds")
                .draw();
            let _ = chart.draw_series(LineSeries::new(
                by_modes.iter().copied(),
                BLUE.stroke_width(2),
            ));
            let _ = chart.draw_series(by_modes.iter().map(|&p| Circle::new(p, 4, BLUE.filled())));
        }
    }
    let _ = root.present();
    eprintln!("plot: {}", out.display());
}

criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench
}
criterion_main!(benches);
