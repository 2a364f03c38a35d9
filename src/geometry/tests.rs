use super::closest_point::{closest_on_segment, closest_on_triangle};
use super::ray::ray_triangle;
use super::*;

#[test]
fn clustering_decimation_keeps_original_points_and_a_closed_surface() {
    let (points, facets) = uv_sphere(64, 32, |t, p| {
        [
            10.0 * t.cos() * p.cos(),
            10.0 * t.cos() * p.sin(),
            10.0 * t.sin(),
        ]
    });
    let s = Shape {
        name: "sphere".into(),
        points,
        facets,
        landmarks: vec![],
    };
    let (d, kept) = s.decimate_by_clustering(1.5, [0.3, 0.1, 0.7]).unwrap();
    assert!(
        d.points.len() < s.points.len() / 2,
        "{} points",
        d.points.len()
    );
    assert_eq!(kept.len(), d.points.len());
    for (p, &k) in d.points.iter().zip(&kept) {
        assert_eq!(*p, s.points[k]);
    }
    // Every edge shared by exactly two facets, each way once (closed, oriented).
    let mut edges = std::collections::HashMap::new();
    for f in &d.facets {
        for e in 0..3 {
            *edges.entry((f[e], f[(e + 1) % 3])).or_insert(0) += 1;
        }
    }
    assert!(
        edges
            .iter()
            .all(|(&(a, b), &c)| c == 1 && edges.get(&(b, a)) == Some(&1))
    );
    assert!(s.decimate_by_clustering(0.0, [0.0; 3]).is_err());
}

#[test]
fn hinted_closest_points_equal_the_plain_ones() {
    // A wiggly closed outline, queries near and far, hints good and bad.
    let pts: Vec<Point<2>> = (0..400)
        .map(|i| {
            let t = i as f64 / 400.0 * std::f64::consts::TAU;
            let r = 1.0 + 0.3 * (5.0 * t).sin();
            [r * t.cos(), r * t.sin()]
        })
        .collect();
    let s = Shape::polyline("w", pts, true);
    let idx = ClosestPointIndex::from_shape(&s);
    for k in 0..500 {
        let a = k as f64 * 0.7;
        let q = [1.6 * (a * 1.3).cos() * (k % 7) as f64 / 5.0, 1.4 * a.sin()];
        let plain = idx.closest(&q);
        for hint in [0, 57, 399, (k * 13) % 400] {
            let h = idx.closest_from(&q, hint);
            assert!(
                (h.dist2 - plain.dist2).abs() <= 1e-15 * (1.0 + plain.dist2),
                "query {q:?} hint {hint}: {} vs {}",
                h.dist2,
                plain.dist2
            );
        }
    }
}

#[test]
fn memo_queries_equal_plain_ones_as_points_and_surface_move() {
    // A bumpy closed surface whose shape changes from step to step (refit), and query
    // points that drift, jump now and then, and sit near and far.
    let surface = |t: f64| {
        uv_sphere(24, 16, |th, ph| {
            let r = 1.0 + 0.2 * (3.0 * ph + t).cos() * th.cos() + 0.05 * t;
            [
                r * th.cos() * ph.cos(),
                0.8 * r * th.cos() * ph.sin(),
                r * th.sin(),
            ]
        })
    };
    let (points, facets) = surface(0.0);
    let mut idx = ClosestPointIndex::new(&points, &facets);
    let queries = |step: usize| -> Vec<Point<3>> {
        (0..300)
            .map(|k| {
                let a = k as f64 * 0.37 + 0.001 * step as f64;
                let r = 0.6 + (k % 9) as f64 * 0.1 + if step % 7 == 3 { 0.3 } else { 0.0 };
                [r * a.cos(), r * (1.3 * a).sin(), r * (0.7 * a).cos()]
            })
            .collect()
    };
    let mut memos = vec![QueryMemo::default(); 300];
    let mut hits = 0;
    let mut now = points.clone();
    for step in 0..20 {
        if step % 4 == 2 {
            now = surface(0.002 * step as f64).0;
            idx.refit(&now);
        }
        for (q, memo) in queries(step).iter().zip(&mut memos) {
            let before = *memo;
            let m = idx.closest_memo(q, memo);
            let plain = idx.closest(q);
            assert!(
                (m.dist2 - plain.dist2).abs() <= 1e-12 * (1.0 + plain.dist2),
                "step {step} query {q:?}: {} vs {}",
                m.dist2,
                plain.dist2
            );
            // Against every facet of the surface as it is now (not the index's copy),
            // and the answer's facet and weights give its point.
            if step % 4 == 2 {
                let brute = facets
                    .iter()
                    .map(|f| {
                        let w = closest_on_triangle(*q, now[f[0]], now[f[1]], now[f[2]]);
                        let c = (0..3).fold([0.0; 3], |c, k| add(c, scale(now[f[k]], w[k])));
                        dist2(*q, c)
                    })
                    .fold(f64::INFINITY, f64::min);
                assert!((m.dist2 - brute).abs() <= 1e-12 * (1.0 + brute));
                let f = facets[m.facet];
                let at = (0..3).fold([0.0; 3], |c, k| add(c, scale(now[f[k]], m.weights[k])));
                assert!(dist2(at, m.point) < 1e-24, "step {step} query {q:?}");
            }
            hits += usize::from(memo.at == before.at && before.index != 0);
        }
    }
    // The memos did answer most queries without a search.
    assert!(hits > 1500, "only {hits} memo answers of 6000");
    // A memo from another index is not trusted.
    let other = ClosestPointIndex::new(&points, &facets);
    let q = [2.0, 0.0, 0.0];
    let mut memo = QueryMemo::default();
    let _ = idx.closest_memo(&q, &mut memo);
    let c = other.closest_memo(&q, &mut memo);
    assert!((c.dist2 - other.closest(&q).dist2).abs() < 1e-12);
}

#[test]
fn the_index_normals_follow_the_surface_through_refits() {
    // The index's own vertex normals (kept in its corner order) against those of the
    // shape's arrays, before and after the surface moves.
    let surface = |t: f64| {
        uv_sphere(20, 12, |th, ph| {
            let r = 1.0 + 0.3 * (2.0 * ph + t).sin() * th.cos();
            [
                r * th.cos() * ph.cos(),
                r * th.cos() * ph.sin(),
                0.7 * r * th.sin(),
            ]
        })
    };
    let (points, facets) = surface(0.0);
    let mut idx = ClosestPointIndex::new(&points, &facets);
    let mut out = Vec::new();
    for t in [0.0, 0.5, 1.5] {
        let now = surface(t).0;
        idx.refit(&now);
        let vn = vertex_normals(&now, &facets);
        idx.vertex_normals_into(&mut out);
        assert_eq!(out.len(), vn.len());
        for (a, b) in out.iter().zip(&vn) {
            assert!(dist2(*a, *b) < 1e-24);
        }
        for k in 0..200 {
            let a = k as f64 * 0.61;
            let q = [1.5 * a.cos(), 1.3 * (0.9 * a).sin(), (0.4 * a).cos() - 0.2];
            let c = idx.closest(&q);
            let f = facets[c.facet];
            assert_eq!(idx.facet_vertices(&c), Some(f));
            let blend = (0..3).fold([0.0; 3], |n, i| add(n, scale(vn[f[i]], c.weights[i])));
            let n = idx.normal_at(&c).expect("no degenerate facet here");
            assert!(dist2(n, normalize(blend)) < 1e-20, "t {t} query {q:?}");
        }
    }
}

#[test]
fn rays_agree_with_brute_force() {
    // A bumpy closed surface, rays in every direction and along the axes (zero
    // components: the slab test's infinite bounds), from inside, outside and far.
    let (points, facets) = uv_sphere(18, 11, |th, ph| {
        let r = 1.0 + 0.25 * (3.0 * ph).sin() * th.cos();
        [
            r * th.cos() * ph.cos(),
            r * th.cos() * ph.sin(),
            0.8 * r * th.sin(),
        ]
    });
    let idx = ClosestPointIndex::new(&points, &facets);
    let mut hits = 0;
    for k in 0..400 {
        let a = k as f64 * 0.37;
        let p = [
            1.8 * (0.7 * a).cos() * (k % 5) as f64 / 4.0,
            1.5 * (1.1 * a).sin() * (k % 3) as f64 / 2.0,
            (0.3 * a).cos() - 0.1,
        ];
        let n = match k % 4 {
            0 => [1.0, 0.0, 0.0],
            1 => [0.0, -1.0, 0.0],
            2 => [0.0, 0.6, 0.8],
            _ => normalize([a.cos(), (2.0 * a).sin(), 0.5 - (k % 7) as f64 / 7.0]),
        };
        let max_t = 0.3 + (k % 6) as f64 * 0.4;
        let brute = facets
            .iter()
            .filter_map(|f| ray_triangle(p, n, points[f[0]], points[f[1]], points[f[2]]))
            .map(|(t, _)| t.abs())
            .filter(|t| *t <= max_t)
            .fold(f64::INFINITY, f64::min);
        match idx.ray(&p, &n, max_t) {
            Some(h) => {
                hits += 1;
                assert!((h.dist2.sqrt() - brute).abs() < 1e-12, "ray {k}");
            }
            None => assert!(brute.is_infinite(), "ray {k} missed a hit at {brute}"),
        }
    }
    assert!(hits > 100, "only {hits} rays hit");
}

#[test]
fn closest_point_on_segments_is_exact_not_vertex() {
    // A long segment: the closest point is in its middle, far from both vertices.
    let s = Shape::polyline("l", vec![[0.0, 0.0], [10.0, 0.0], [10.0, 1.0]], false);
    let idx = ClosestPointIndex::from_shape(&s);
    let c = idx.closest(&[4.0, 2.0]);
    assert!((c.point[0] - 4.0).abs() < 1e-12 && c.point[1].abs() < 1e-12);
    assert!((c.dist2 - 4.0).abs() < 1e-12);
}

#[test]
fn closest_point_agrees_with_brute_force() {
    let n = 200;
    let pts: Vec<Point<2>> = (0..n)
        .map(|i| {
            let t = i as f64 / n as f64 * std::f64::consts::TAU;
            let r = 1.0 + 0.3 * (5.0 * t).cos();
            [r * t.cos(), r * t.sin()]
        })
        .collect();
    let s = Shape::polyline("star", pts, true);
    let idx = ClosestPointIndex::from_shape(&s);
    for k in 0..500 {
        let q = [
            ((k * 37) % 101) as f64 / 40.0 - 1.25,
            ((k * 53) % 97) as f64 / 38.0 - 1.25,
        ];
        let c = idx.closest(&q);
        // Straight from the shape's own points, not the index's copies.
        let brute = s
            .facets
            .iter()
            .map(|f| {
                let (a, b) = (s.points[f[0]], s.points[f[1]]);
                let t = closest_on_segment(q, a, b);
                dist2(q, add(a, scale(sub(b, a), t)))
            })
            .fold(f64::INFINITY, f64::min);
        assert!((c.dist2 - brute).abs() < 1e-12, "query {q:?}");
    }
}

#[test]
fn similarity_inverse_undoes_apply() {
    let mut t = Similarity::<2>::planar_rotation(0.7);
    t.s = 2.5;
    t.t = [1.0, -3.0];
    let p = [0.3, 0.9];
    let q = t.apply_inverse(&t.apply(&p));
    assert!(dist2(p, q) < 1e-24);
}

#[test]
fn ccw_circle_normals_point_outwards() {
    let pts: Vec<Point<2>> = (0..50)
        .map(|i| {
            let t = i as f64 / 50.0 * std::f64::consts::TAU;
            [t.cos(), t.sin()]
        })
        .collect();
    let s = Shape::polyline("c", pts.clone(), true);
    for (p, n) in pts.iter().zip(s.vertex_normals()) {
        assert!(dot(*p, n) > 0.99);
    }
}

#[test]
fn names_are_shown_without_hidden_characters_and_cut_with_a_checksum() {
    use super::{MAX_NAME_CHARS, display_name};
    assert_eq!(display_name("S001_Femur"), "S001_Femur");
    assert_eq!(display_name("fémur ü"), "fémur ü");
    // A right-to-left override (display spoofing), a zero-width space, a newline.
    assert_eq!(display_name("a\u{202E}gpj.exe"), "a\u{FFFD}gpj.exe");
    assert_eq!(display_name("a\u{200B}b\nc"), "a\u{FFFD}b\u{FFFD}c");
    let long_a = "a".repeat(10_000);
    let long_b = format!("{}b", "a".repeat(9_999));
    let (a, b) = (display_name(&long_a), display_name(&long_b));
    assert_eq!(a.chars().count(), MAX_NAME_CHARS);
    assert_ne!(a, b);
}
