//! The paper's hand experiment (section 6.1) on the IMM hands in `$ATLASMESH_DATA`.

use crate::common;

use atlasmesh::ffd::FfdParams;
use atlasmesh::fit::{FitParams, Fitter};
use atlasmesh::formats::read_outlines;
use atlasmesh::geometry::{ClosestPointIndex, Point, Shape};
use atlasmesh::mesh::quad_mesh::boundary_nodes;
use atlasmesh::model::generalized_procrustes;
use atlasmesh::model::pca;
use atlasmesh::model::{Atlas, AtlasParams, ModeSelection};
use atlasmesh::study::{RunParams, leave_one_out};

/// GPA with tangent projection + PCA of the 40 × 56 landmarks: the first mode explains
/// 0.663 of the variance (the IMM note's "66 %"; value verified in the data's README).
#[test]
fn first_mode_of_the_40_hands_explains_66_percent() {
    let Some(data) = common::data_dir("first_mode_of_the_40_hands_explains_66_percent") else {
        return;
    };
    let shapes = read_outlines(&data.join("imm-hands-2d/hands_long.csv"), false).unwrap();
    assert_eq!(shapes.len(), 40);
    assert!(shapes.iter().all(|s| s.points.len() == 56));
    let pts: Vec<Vec<Point<2>>> = shapes.iter().map(|s| s.points.clone()).collect();
    let g = generalized_procrustes(&pts).unwrap();
    let p = pca(&g.aligned, &g.mean).unwrap();
    let share = p.cumulative_variance()[0];
    assert!((share - 0.663).abs() < 0.01, "first mode share {share}");
    // The next two modes, from the same README: 0.176 and 0.079.
    let c = p.cumulative_variance();
    assert!(
        (c[1] - c[0] - 0.176).abs() < 0.01 && (c[2] - c[1] - 0.079).abs() < 0.01,
        "{:?}",
        &c[..3]
    );
}

/// Resampling to 2001 points keeps the 56 landmarks at the same indices on every hand.
#[test]
fn resampled_hands_keep_their_landmarks() {
    let Some(data) = common::data_dir("resampled_hands_keep_their_landmarks") else {
        return;
    };
    let raw = read_outlines(&data.join("imm-hands-2d/hands_long.csv"), false).unwrap();
    let shapes: Vec<Shape<2>> = common::hands(&data, Some(2001));
    assert_eq!(shapes.len(), 40);
    for (s, r) in shapes.iter().zip(&raw) {
        assert_eq!(s.points.len(), 2001);
        assert_eq!(s.landmarks.len(), 56);
        for (l, p) in s.landmarks.iter().zip(&r.points) {
            assert_eq!(s.points[*l], *p);
        }
        assert_eq!(s.landmarks, shapes[0].landmarks);
    }
}

/// The leave-one-out of section 6.1 with the paper's settings (2001 points, 11 modes).
/// Regression figures of the current method (closing note of issue 2): every morphed mesh is
/// valid and at least 36 of the 40 fits are within 1 % two-way RMS of their subject (the paper
/// reported 39 by eye; a one-way transcription of Algorithm 1 reaches 33-34 by this measure).
#[test]
fn hands_leave_one_out() {
    let Some(data) = common::data_dir("hands_leave_one_out") else {
        return;
    };
    let shapes = common::hands(&data, Some(2001));
    let mut params = RunParams::default();
    params.atlas.modes = atlasmesh::model::ModeSelection::Count(11);
    params.plots = false;
    let out = common::temp_dir("hands-loo");
    let r = leave_one_out(
        &shapes,
        "imm-hands-2d",
        &params,
        &out,
        0,
        &atlasmesh::study::Silent,
    )
    .unwrap();
    assert_eq!(r.summary.subjects, 40);
    common::assert_repaired("hands", &r);
    assert_eq!(
        r.summary.meshes_valid, 40,
        "every morphed mesh has positive corner Jacobians"
    );
    assert_eq!(
        r.summary.succeeded, 40,
        "every hand fitted, and its mesh within 1 % of its diagonal (RMS)"
    );
    assert_eq!(common::assert_delivered(&r, &out, &shapes), 40);
    assert!(r.summary.median_rms_distance_relative < 0.005);
    assert!(r.summary.median_normal_correlation > 0.95);
    let cycling: Vec<&str> = r
        .subjects
        .iter()
        .filter(|s| !s.converged)
        .map(|s| s.name.as_str())
        .collect();
    assert!(
        cycling.is_empty(),
        "fits that missed the tolerance at the last gamma: {cycling:?}"
    );
    assert_eq!(r.modes, 11);
    assert!(
        r.variance_explained[10] > 0.98,
        "11 modes explain {}",
        r.variance_explained[10]
    );
    let mm = r.mean_mesh.as_ref().unwrap();
    assert!(
        mm.scaled_jacobian_min >= 0.3,
        "mean mesh min scaled Jacobian {}",
        mm.scaled_jacobian_min
    );
    // The report's fixed field names are there for scripts.
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    for k in [
        "dataset",
        "dimension",
        "modes",
        "variance_explained",
        "parameters",
        "subjects",
        "summary",
    ] {
        assert!(json.get(k).is_some(), "report.json lacks {k}");
    }
    for k in [
        "name",
        "iterations",
        "fit_seconds",
        "e_d",
        "rms_distance",
        "rms_distance_relative",
        "normal_correlation",
        "jacobian_min",
        "scaled_jacobian_min",
        "inverted_elements",
        "success",
    ] {
        assert!(json["subjects"][0].get(k).is_some(), "subject lacks {k}");
    }
    assert!(out.join("0_mesh.vtu").is_file());
    std::fs::remove_dir_all(&out).ok();
}

/// The dense Basel hands: binary big-endian legacy VTK outlines are read in loop order.
#[test]
fn basel_binary_vtk_hands_are_read() {
    let Some(data) = common::data_dir("basel_binary_vtk_hands_are_read") else {
        return;
    };
    for k in 0..12 {
        let s = read_outlines(
            &data.join(format!(
                "unibas-hands-2d-dense/registered/mesh/hand-{k}.vtk"
            )),
            true,
        )
        .unwrap();
        assert_eq!(s[0].points.len(), 2125);
        assert!(s[0].is_closed());
        // Chain order: consecutive points are close; the one long segment is the wrist, which
        // closes the loop in these files.
        let med = s[0].median_edge_length();
        let long = s[0]
            .facets
            .iter()
            .filter(|f| {
                atlasmesh::geometry::norm(atlasmesh::geometry::sub(
                    s[0].points[f[1]],
                    s[0].points[f[0]],
                )) > 20.0 * med
            })
            .count();
        assert!(
            long <= 1,
            "hand-{k}: {long} segments longer than 20 median lengths"
        );
    }
}

/// The morphed mesh follows the subject: its boundary nodes lie on the subject's outline
/// (the wrist chord, which closes the open outline, aside). Subjects 0 (typical) and 37
/// (the paper's S38, the outlier that Algorithm 1 failed on).
#[test]
fn morphed_mesh_boundary_lies_on_the_subject() {
    let Some(data) = common::data_dir("morphed_mesh_boundary_lies_on_the_subject") else {
        return;
    };
    let shapes = common::hands(&data, Some(2001));
    for k in [0usize, 37] {
        let train: Vec<_> = shapes
            .iter()
            .enumerate()
            .filter(|(i, _)| *i != k)
            .map(|(_, s)| s.clone())
            .collect();
        let atlas = Atlas::build(
            &train,
            &AtlasParams {
                modes: ModeSelection::Count(11),
                ..AtlasParams::default()
            },
        )
        .unwrap();
        let subject = &shapes[k];
        let index = ClosestPointIndex::from_shape(subject);
        let fit = Fitter::new(std::sync::Arc::new(atlas.clone()))
            .fit(subject, &index, &FitParams::default())
            .unwrap();
        let morph = atlas
            .morpher(&FfdParams::default())
            .unwrap()
            .morph(&fit.correspondence())
            .unwrap();
        let on_boundary = boundary_nodes(&morph.mesh);
        let mut d: Vec<f64> = morph
            .mesh
            .nodes
            .iter()
            .zip(&on_boundary)
            .filter(|(_, b)| **b)
            .map(|(p, _)| index.closest(p).dist2.sqrt() / subject.bbox_diagonal())
            .collect();
        d.sort_by(f64::total_cmp);
        let (median, p90) = (d[d.len() / 2], d[d.len() * 9 / 10]);
        eprintln!(
            "subject {k}: boundary to subject median {median:.5}, p90 {p90:.5} (of the diagonal)"
        );
        assert!(median < 0.002, "subject {k}: median {median}");
        assert!(p90 < 0.01, "subject {k}: 90th percentile {p90}");
    }
}

/// A leave-one-out at several numbers of modes (each fold's atlas built once) reports what
/// separate leave-one-outs report: 12 hands (1001 points), 6 and 3 modes, every subject's
/// fitted and delivered distances and mesh quality the same to the last bit.
#[test]
fn a_leave_one_out_by_modes_is_the_runs_one_at_a_time() {
    let Some(data) = common::data_dir("a_leave_one_out_by_modes_is_the_runs_one_at_a_time") else {
        return;
    };
    let shapes: Vec<_> = common::hands(&data, Some(1001))
        .into_iter()
        .take(12)
        .collect();
    let mut params = RunParams {
        plots: false,
        ..Default::default()
    };
    let out = common::temp_dir("hands-loo-by-modes");
    let both = atlasmesh::study::leave_one_out_by_modes(
        atlasmesh::study::Folds::of(&shapes),
        "imm-hands-2d",
        &params,
        &[6, 3],
        &out,
        0,
        &atlasmesh::study::Silent,
    )
    .unwrap();
    assert_eq!(both.len(), 2);
    for (modes, r) in [6, 3].into_iter().zip(&both) {
        params.atlas.modes = ModeSelection::Count(modes);
        let alone = common::temp_dir("hands-loo-alone");
        let one = leave_one_out(
            &shapes,
            "imm-hands-2d",
            &params,
            &alone,
            0,
            &atlasmesh::study::Silent,
        )
        .unwrap();
        assert_eq!(r.modes, modes);
        assert_eq!(r.subjects.len(), 12, "{modes} modes: {:?}", r.failed);
        assert_eq!(one.subjects.len(), 12);
        // The same to the last bit: a run is reproducible, and the shared fold's atlas is
        // the one a run with that many modes builds.
        let close = |a: f64, b: f64| a.to_bits() == b.to_bits();
        for (a, b) in r.subjects.iter().zip(&one.subjects) {
            assert_eq!(a.name, b.name);
            assert!(
                close(a.rms_distance, b.rms_distance)
                    && close(a.mesh_rms_distance, b.mesh_rms_distance)
                    && close(a.scaled_jacobian_min, b.scaled_jacobian_min),
                "{modes} modes, {}: fit {} / {}, mesh {} / {}, quality {} / {}",
                a.name,
                a.rms_distance,
                b.rms_distance,
                a.mesh_rms_distance,
                b.mesh_rms_distance,
                a.scaled_jacobian_min,
                b.scaled_jacobian_min
            );
        }
        // Each report in its own folder, with its subjects' meshes.
        let dir = out.join(format!("modes-{modes}"));
        assert!(dir.join("report.json").is_file());
        assert_eq!(common::assert_delivered(r, &dir, &shapes), 12);
        let _ = std::fs::remove_dir_all(&alone);
    }
    let _ = std::fs::remove_dir_all(&out);
}
