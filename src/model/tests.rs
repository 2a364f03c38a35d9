use super::*;
use crate::geometry::{Point, Shape};
use faer::Mat;
use faer::linalg::solvers::Solve;

pub(crate) fn ellipses(n: usize) -> Vec<Shape<2>> {
    (0..n)
        .map(|k| {
            let a = 1.0 + 0.2 * (k as f64 * 1.7).sin();
            let b = 0.6 + 0.1 * (k as f64 * 2.3).cos();
            let bump = 0.1 * (k as f64 * 0.9).cos();
            let lobe = 0.08 * (k as f64 * 1.1).sin();
            let pts = (0..80)
                .map(|i| {
                    let t = i as f64 / 80.0 * std::f64::consts::TAU;
                    [
                        a * t.cos() + bump * (3.0 * t).cos(),
                        b * t.sin() + lobe * (2.0 * t).sin(),
                    ]
                })
                .collect();
            Shape::polyline(format!("e{k}"), pts, true)
        })
        .collect()
}

#[test]
fn a_model_instance_gives_back_its_weights() {
    let atlas = Atlas::build(
        &ellipses(8),
        &AtlasParams {
            modes: ModeSelection::Count(3),
            element_size: 0.05,
            smoothing_passes: 2,
        },
    )
    .unwrap();
    let w: Vec<f64> = atlas
        .eigenvalues
        .iter()
        .enumerate()
        .map(|(k, l)| l.sqrt() * (k as f64 - 1.0))
        .collect();
    let x = atlas.instance(&w);
    let back = atlas.coefficients(&x);
    for (a, b) in w.iter().zip(&back) {
        assert!((a - b).abs() < 1e-12);
    }
}

#[test]
fn atlas_survives_a_save_load_round_trip() {
    let atlas = Atlas::build(
        &ellipses(6),
        &AtlasParams {
            modes: ModeSelection::Count(2),
            element_size: 0.05,
            smoothing_passes: 2,
        },
    )
    .unwrap();
    let tmp = tempfile::Builder::new()
        .prefix("atlasmesh-test-")
        .tempdir()
        .unwrap();
    let dir = tmp.path();
    let p = dir.join("a.safetensors");
    atlas.save(&p).unwrap();
    let b = Atlas::<2>::load(&p).unwrap();
    assert_eq!(atlas.mean, b.mean);
    assert_eq!(atlas.modes, b.modes);
    assert_eq!(atlas.mesh, b.mesh);
    assert_eq!(atlas.params, b.params);
    assert!(Atlas::<3>::load(&p).unwrap_err().to_string().contains("2D"));
    std::fs::write(&p, b"garbage").unwrap();
    assert!(Atlas::<2>::load(&p).is_err());
}

/// The same population gives the same atlas file, byte for byte: neither the mean mesh's
/// smoothing nor the file's header follows a hash map's order (new for every map).
#[test]
fn the_same_population_gives_the_same_atlas_file() {
    let build = || {
        Atlas::build(
            &ellipses(8),
            &AtlasParams {
                modes: ModeSelection::Count(3),
                element_size: 0.05,
                smoothing_passes: 4,
            },
        )
        .unwrap()
        .to_bytes()
        .unwrap()
    };
    let first = build();
    for _ in 0..4 {
        assert!(
            build() == first,
            "another atlas file from the same population"
        );
    }
    let header = u64::from_le_bytes(first[..8].try_into().unwrap());
    assert_eq!(header % 8, 0, "the header padded to 8 bytes");
    let back = Atlas::<2>::from_bytes(std::path::Path::new("a.safetensors"), &first).unwrap();
    assert_eq!(back.to_bytes().unwrap(), first);
}

fn three_mode_atlas() -> Atlas<2> {
    Atlas::build(
        &ellipses(10),
        &AtlasParams {
            modes: ModeSelection::Count(3),
            element_size: 0.05,
            smoothing_passes: 2,
        },
    )
    .unwrap()
}

#[test]
fn project_and_truncate() {
    let atlas = three_mode_atlas();
    let shapes = ellipses(10);
    let gpa = generalized_procrustes(&shapes.iter().map(|s| s.points.clone()).collect::<Vec<_>>())
        .unwrap();
    // A shape of the span projects onto itself; the projection of any shape is the instance
    // of its coefficients, and projecting twice changes nothing.
    let w = [0.3, -0.2, 0.1];
    let w: Vec<f64> = (0..3).map(|k| w[k] * atlas.eigenvalues[k].sqrt()).collect();
    let x = atlas.instance(&w);
    let p = atlas.project(&x);
    assert!(
        x.iter()
            .zip(&p)
            .all(|(a, b)| crate::geometry::dist2(*a, *b) < 1e-24)
    );
    let y = align_to_mean(&shapes[3].points, &gpa.mean);
    let py = atlas.project(&y);
    assert_eq!(py, atlas.instance(&atlas.coefficients(&y)));
    let ppy = atlas.project(&py);
    assert!(
        py.iter()
            .zip(&ppy)
            .all(|(a, b)| crate::geometry::dist2(*a, *b) < 1e-24)
    );
    // Truncation keeps the first modes.
    let t = atlas.truncate(2).unwrap();
    assert_eq!(t.num_modes(), 2);
    assert_eq!(t.eigenvalues, atlas.eigenvalues[..2]);
    assert_eq!(t.instance(&w[..2]), atlas.instance(&[w[0], w[1], 0.0]));
    assert!(atlas.truncate(0).is_err() && atlas.truncate(4).is_err());
    assert_eq!(atlas.mean(), &atlas.mean[..]);
}

#[test]
fn samples_follow_the_prior_and_its_bound() {
    use rand::SeedableRng;
    let atlas = three_mode_atlas();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let n = 4000;
    let draws: Vec<Vec<f64>> = (0..n)
        .map(|_| atlas.sample_weights(&mut rng, None).unwrap())
        .collect();
    for k in 0..3 {
        let var = draws.iter().map(|w| w[k] * w[k]).sum::<f64>() / n as f64;
        let ratio = var / atlas.eigenvalues[k];
        // The variance of a sample variance of n normal draws is 2/n: 5 standard errors.
        assert!(
            (ratio - 1.0).abs() < 5.0 * (2.0 / n as f64).sqrt(),
            "mode {k}: {ratio}"
        );
    }
    for _ in 0..500 {
        let w = atlas.sample_weights(&mut rng, Some(1.0)).unwrap();
        for k in 0..3 {
            assert!(w[k].abs() <= atlas.eigenvalues[k].sqrt() * (1.0 + 1e-12));
        }
    }
    let mut again = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    assert_eq!(
        atlas.sample(&mut again, None).unwrap(),
        atlas.instance(&draws[0])
    );
    assert!(atlas.sample_weights(&mut rng, Some(f64::NAN)).is_err());
    assert!(atlas.sample_weights(&mut rng, Some(0.1)).is_err());
}

/// The posterior of the weights against the Gaussian-process form of the same conditioning
/// in point space: `mu + K_{.I} (K_II + sigma2 I)^-1 (y - mu_I)` with `K = Psi Lambda Psi^T`,
/// and the covariance `K - K_{.I} (K_II + sigma2 I)^-1 K_{I.}`.
#[test]
fn the_posterior_is_the_gaussian_conditioning() {
    let atlas = three_mode_atlas();
    let n = atlas.mean.len();
    let m = atlas.num_modes();
    let nd = 2 * n;
    let k = {
        let l = Mat::from_fn(m, m, |a, b| if a == b { atlas.eigenvalues[a] } else { 0.0 });
        &atlas.modes * &l * atlas.modes.transpose()
    };
    // A shape of the model, observed at 4 points with some noise added.
    let w = [0.5, -0.4, 0.3];
    let w: Vec<f64> = (0..m).map(|i| w[i] * atlas.eigenvalues[i].sqrt()).collect();
    let truth = atlas.instance(&w);
    let idx = [3usize, 21, 40, 66];
    let observed: Vec<(usize, [f64; 2])> = idx
        .iter()
        .enumerate()
        .map(|(j, &i)| (i, [truth[i][0] + 1e-3 * j as f64, truth[i][1] - 5e-4]))
        .collect();
    let sigma2 = 1e-4;
    let post = atlas.posterior(&observed, sigma2).unwrap();
    // Point-space form.
    let rows: Vec<usize> = idx.iter().flat_map(|&i| [2 * i, 2 * i + 1]).collect();
    let r = rows.len();
    let kii = Mat::from_fn(r, r, |a, b| {
        k[(rows[a], rows[b])] + if a == b { sigma2 } else { 0.0 }
    });
    let kxi = Mat::from_fn(nd, r, |a, b| k[(a, rows[b])]);
    let resid = Mat::from_fn(r, 1, |a, _| {
        let (i, d) = (idx[a / 2], a % 2);
        observed[a / 2].1[d] - atlas.mean[i][d]
    });
    let llt = kii.llt(faer::Side::Lower).unwrap();
    let mean = &kxi * llt.solve(&resid);
    let cov = &k - &kxi * llt.solve(kxi.transpose());
    for i in 0..n {
        for d in 0..2 {
            let gp = atlas.mean[i][d] + mean[(2 * i + d, 0)];
            assert!(
                (gp - post.mean[i][d]).abs() < 1e-9,
                "point {i}: {gp} vs {}",
                post.mean[i][d]
            );
        }
        let sd = (cov[(2 * i, 2 * i)] + cov[(2 * i + 1, 2 * i + 1)])
            .max(0.0)
            .sqrt();
        assert!(
            (sd - post.point_sd[i]).abs() < 1e-7,
            "point {i}: sd {sd} vs {}",
            post.point_sd[i]
        );
    }
    // The observed points are pulled to the observations; the spread is smallest there.
    for (i, p) in &observed {
        assert!(crate::geometry::dist2(post.mean[*i], *p).sqrt() < 0.02);
    }
    // With no observation: the prior.
    let prior = atlas.posterior(&[], sigma2).unwrap();
    assert!(prior.weights.iter().all(|w| *w == 0.0));
    let mg = atlas.marginal(&[5]).unwrap();
    let c = mg.covariance(0);
    assert!((prior.point_sd[5] - (c[0][0] + c[1][1]).sqrt()).abs() < 1e-12);
    // Bad input.
    assert!(atlas.posterior(&observed, 0.0).is_err());
    assert!(atlas.posterior(&[(n, [0.0, 0.0])], sigma2).is_err());
    assert!(
        atlas
            .posterior(&[(1, [0.0, 0.0]), (1, [0.0, 0.0])], sigma2)
            .is_err()
    );
    assert!(atlas.posterior(&[(1, [f64::NAN, 0.0])], sigma2).is_err());
}

#[test]
fn the_marginal_keeps_the_rows_of_its_points() {
    let atlas = three_mode_atlas();
    let w = [0.2, 0.1, -0.3];
    let mg = atlas.marginal(&[7, 2, 50]).unwrap();
    let full = atlas.instance(&w);
    assert_eq!(mg.instance(&w), vec![full[7], full[2], full[50]]);
    assert!(atlas.marginal(&[]).is_err());
    assert!(atlas.marginal(&[atlas.mean.len()]).is_err());
}

/// The atlas knows the data's frame and unit: the mean carried by its data frame lies on the
/// average of the shapes (which share one pose here), at their size; the frame survives a
/// save and load, and an atlas without it is one of format version 2.
#[test]
fn the_atlas_knows_the_data_frame() {
    let t = crate::geometry::Similarity::<2>::centred(
        25.0,
        crate::geometry::Similarity::<2>::planar_rotation(0.4).r,
        &[0.0, 0.0],
        &[120.0, -40.0],
    );
    let shapes: Vec<Shape<2>> = ellipses(8)
        .into_iter()
        .map(|mut s| {
            s.points = s.points.iter().map(|p| t.apply(p)).collect();
            s
        })
        .collect();
    let atlas = Atlas::build(
        &shapes,
        &AtlasParams {
            modes: ModeSelection::Count(2),
            element_size: 0.05,
            smoothing_passes: 2,
        },
    )
    .unwrap();
    let frame = atlas.data_frame.unwrap();
    let mean = atlas.to_data_frame(&atlas.mean);
    let n = shapes.len() as f64;
    let average: Vec<[f64; 2]> = (0..mean.len())
        .map(|i| {
            let s = shapes.iter().fold([0.0; 2], |a, s| {
                [a[0] + s.points[i][0], a[1] + s.points[i][1]]
            });
            [s[0] / n, s[1] / n]
        })
        .collect();
    // The shapes differ by about 20 % in size: the mean lies within 2 % of their extent
    // (about 50 units) of their average.
    for (a, b) in mean.iter().zip(&average) {
        assert!(
            crate::geometry::dist2(*a, *b).sqrt() < 1.0,
            "{a:?} vs {b:?}"
        );
    }
    // The reference mean has a largest side of 1: the data's extent is about 2 × 25 × 1.1.
    assert!(frame.s > 40.0 && frame.s < 70.0, "{}", frame.s);
    let tmp = tempfile::Builder::new()
        .prefix("atlasmesh-frame-")
        .tempdir()
        .unwrap();
    let dir = tmp.path();
    let p = dir.join("a.safetensors");
    atlas.save(&p).unwrap();
    let back = Atlas::<2>::load(&p).unwrap();
    assert_eq!(back.data_frame, atlas.data_frame);
    let mut old = atlas.clone();
    old.data_frame = None;
    let bytes = old.to_bytes().unwrap();
    assert!(bytes.windows(20).any(|w| w == b"\"format_version\":\"2\""));
    let back = Atlas::<2>::from_bytes(&p, &bytes).unwrap();
    assert_eq!(back.data_frame, None);
    assert_eq!(back.to_data_frame(&back.mean), back.mean);
}

#[test]
fn atlases_with_an_absurd_scale_or_a_landmark_id_twice_do_not_load() {
    let path = std::path::Path::new("edited.safetensors");
    let mut a = three_mode_atlas();
    a.data_frame = Some(crate::geometry::Similarity::<2>::centred(
        1e300,
        crate::geometry::Similarity::<2>::planar_rotation(0.0).r,
        &[0.0, 0.0],
        &[0.0, 0.0],
    ));
    let e = Atlas::<2>::from_bytes(path, &a.to_bytes().unwrap())
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("edited.safetensors") && e.contains("scale from 1e-9"),
        "{e}"
    );
    let mut b = three_mode_atlas();
    b.landmarks = vec![0, 5];
    b.landmark_ids = vec!["tip".into(), "tip".into()];
    let e = Atlas::<2>::from_bytes(path, &b.to_bytes().unwrap())
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("\"tip\" is given twice"), "{e}");
}

/// `n` closed outlines of 60 points with `modes` deformation modes of decaying size
/// (harmonics of amplitude `decay^k` times a random normal) and a random pose (rotation,
/// scale 0.5-2, translation): a population whose spectrum decays as the shared populations'
/// do.
fn posed_outlines(n: usize, seed: u64) -> Vec<Vec<Point<2>>> {
    outlines_with_modes(n, seed, 12, 0.6)
}

fn outlines_with_modes(n: usize, seed: u64, modes: usize, decay: f64) -> Vec<Vec<Point<2>>> {
    use rand::SeedableRng;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            let w: Vec<f64> = (0..modes)
                .map(|k| decay.powi(k as i32) * 0.1 * standard_normal(&mut rng))
                .collect();
            let angle = 3.0 * standard_normal(&mut rng);
            let s = 1.25 + 0.75 * standard_normal(&mut rng).tanh();
            let shift = [standard_normal(&mut rng), standard_normal(&mut rng)];
            let mut pose = crate::geometry::Similarity::<2>::planar_rotation(angle);
            pose.s = s;
            pose.t = shift;
            (0..60)
                .map(|i| {
                    let t = i as f64 / 60.0 * std::f64::consts::TAU;
                    let r: f64 = 1.0
                        + w.iter()
                            .enumerate()
                            .map(|(k, a)| a * ((k / 2 + 2) as f64 * t + (k % 2) as f64 * 1.5).cos())
                            .sum::<f64>();
                    pose.apply(&[1.4 * r * t.cos(), r * t.sin()])
                })
                .collect()
        })
        .collect()
}

/// The same mode up to its sign: `|a · b|` of two unit columns.
fn alignment(a: &Mat<f64>, b: &Mat<f64>, k: usize) -> f64 {
    (0..a.nrows())
        .map(|r| a[(r, k)] * b[(r, k)])
        .sum::<f64>()
        .abs()
}

/// The streamed GPA gives the in-memory GPA's mean, whatever the batch.
#[test]
fn the_streamed_procrustes_mean_is_the_in_memory_one() {
    let shapes = posed_outlines(40, 3);
    let dense = generalized_procrustes(&shapes).unwrap();
    for batch in [1, 7, 64] {
        let streamed = generalized_procrustes_streamed(&shapes, batch).unwrap();
        let apart: f64 = dense
            .mean
            .iter()
            .zip(&streamed.mean)
            .map(|(a, b)| crate::geometry::dist2(*a, *b))
            .sum::<f64>()
            .sqrt();
        assert!(apart < 1e-12, "batch {batch}: means {apart} apart");
        assert_eq!(streamed.iterations, dense.iterations, "batch {batch}");
    }
}

fn model_params(modes: ModeSelection) -> AtlasParams {
    AtlasParams {
        modes,
        element_size: 0.05,
        smoothing_passes: 2,
    }
}

fn streamed(shapes: &Vec<Vec<Point<2>>>, modes: ModeSelection, batch: usize) -> Atlas<2> {
    let facets = Shape::polyline("s", shapes[0].clone(), true).facets;
    let stream = StreamParams {
        batch,
        ..StreamParams::default()
    };
    Atlas::build_streamed(
        shapes,
        facets,
        Vec::new(),
        &model_params(modes),
        &stream,
        |_, _| Ok(atlas::no_mesh()),
    )
    .unwrap()
}

fn in_memory(shapes: &[Vec<Point<2>>], modes: ModeSelection) -> Atlas<2> {
    let shapes: Vec<Shape<2>> = shapes
        .iter()
        .enumerate()
        .map(|(k, p)| Shape::polyline(format!("s{k}"), p.clone(), true))
        .collect();
    Atlas::build_model(&shapes, &model_params(modes)).unwrap()
}

/// Where the modes asked and the oversampling reach every mode of the population, the
/// streamed atlas is the in-memory one: mean, eigenvalues, modes (up to their sign),
/// cumulative variance and data frame, to rounding.
#[test]
fn a_streamed_atlas_of_a_small_population_is_the_in_memory_one() {
    let shapes = posed_outlines(12, 5);
    let dense = in_memory(&shapes, ModeSelection::Count(6));
    let s = streamed(&shapes, ModeSelection::Count(6), 5);
    let apart = |a: &[Point<2>], b: &[Point<2>]| {
        a.iter()
            .zip(b)
            .map(|(p, q)| crate::geometry::dist2(*p, *q))
            .fold(0.0, f64::max)
            .sqrt()
    };
    assert!(apart(&dense.mean, &s.mean) < 1e-12);
    for k in 0..6 {
        let rel = s.eigenvalues[k] / dense.eigenvalues[k] - 1.0;
        assert!(rel.abs() < 1e-9, "mode {k}: eigenvalue off by {rel}");
        assert!(
            alignment(&dense.modes, &s.modes, k) > 1.0 - 1e-9,
            "mode {k}"
        );
    }
    for (a, b) in dense.cumulative_variance.iter().zip(&s.cumulative_variance) {
        assert!((a - b).abs() < 1e-9);
    }
    let (fd, fs) = (dense.data_frame.unwrap(), s.data_frame.unwrap());
    assert!((fd.s - fs.s).abs() < 1e-12 * fd.s);
    let x = [0.3, -0.2];
    assert!(crate::geometry::dist2(fd.apply(&x), fs.apply(&x)) < 1e-20);
}

/// With far more shapes and modes than asked (500 shapes of 40 modes decaying by 0.8, 5 modes
/// asked: 15 directions sampled of 119), the randomized PCA finds the dense PCA's leading
/// modes: eigenvalues to 1e-9, modes to 1e-9 in their direction, the variance share of each
/// exact; the same with other batches and seeds.
#[test]
fn the_randomized_modes_of_a_large_population_are_the_dense_ones() {
    let shapes = outlines_with_modes(500, 11, 40, 0.8);
    let dense = in_memory(&shapes, ModeSelection::Count(5));
    for (batch, seed) in [(64, 0), (500, 0), (33, 9)] {
        let facets = Shape::polyline("s", shapes[0].clone(), true).facets;
        let stream = StreamParams {
            batch,
            pca: RandomizedPcaParams {
                seed,
                ..Default::default()
            },
            ..Default::default()
        };
        let s = Atlas::build_streamed(
            &shapes,
            facets,
            Vec::new(),
            &model_params(ModeSelection::Count(5)),
            &stream,
            |_, _| Ok(atlas::no_mesh()),
        )
        .unwrap();
        assert_eq!(s.training_shapes, 500);
        for k in 0..5 {
            let rel = s.eigenvalues[k] / dense.eigenvalues[k] - 1.0;
            assert!(
                rel.abs() < 1e-9,
                "batch {batch}, mode {k}: eigenvalue off by {rel}"
            );
            let a = alignment(&dense.modes, &s.modes, k);
            assert!(a > 1.0 - 1e-9, "batch {batch}, mode {k}: |cos| {a}");
            let share = (s.cumulative_variance[k] - dense.cumulative_variance[k]).abs();
            assert!(share < 1e-9, "mode {k}: cumulative share off by {share}");
        }
    }
}

/// A share of variance the modes computed do not reach is refused with the way out; a shape
/// with a NaN or another point count is refused by its name.
#[test]
fn a_streamed_atlas_refuses_what_it_cannot_model() {
    let shapes = posed_outlines(60, 2);
    let facets = Shape::polyline("s", shapes[0].clone(), true).facets;
    let stream = StreamParams {
        max_modes: 2,
        ..Default::default()
    };
    let build = |shapes: &Vec<Vec<Point<2>>>, modes| {
        Atlas::build_streamed(
            shapes,
            facets.clone(),
            Vec::new(),
            &model_params(modes),
            &stream,
            |_, _| Ok(atlas::no_mesh()),
        )
    };
    let e = build(&shapes, ModeSelection::Variance(0.99))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("--max-modes") && e.contains("2 leading modes"),
        "{e}"
    );
    assert!(build(&shapes, ModeSelection::Variance(0.3)).is_ok());
    let mut bad = shapes.clone();
    bad[17][4][1] = f64::NAN;
    let e = build(&bad, ModeSelection::Count(2))
        .unwrap_err()
        .to_string();
    assert!(e.contains("shape 17") && e.contains("NaN"), "{e}");
    let mut bad = shapes.clone();
    bad[33].pop();
    let e = build(&bad, ModeSelection::Count(2))
        .unwrap_err()
        .to_string();
    assert!(e.contains("shape 33") && e.contains("59 points"), "{e}");
}
