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

/// A k-fold cross-validation of 12 hands (1001 points, 3 modes) in 3 folds: consecutive
/// groups of 4, each subject numbered with its fold; each subject's figures are those of the
/// leave-one-out of its fold's training shapes and itself (whose last fold trains on exactly
/// those shapes), to the last bit; and 12 folds of 12 shapes are the leave-one-out.
#[test]
fn a_k_fold_cross_validation_fits_each_group_with_the_atlas_of_the_others() {
    let Some(data) =
        common::data_dir("a_k_fold_cross_validation_fits_each_group_with_the_atlas_of_the_others")
    else {
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
    params.atlas.modes = ModeSelection::Count(3);
    let same = |a: &atlasmesh::report::SubjectReport, b: &atlasmesh::report::SubjectReport| {
        let bits = |x: f64, y: f64| x.to_bits() == y.to_bits();
        assert_eq!(a.name, b.name);
        assert!(
            bits(a.rms_distance, b.rms_distance)
                && bits(a.mesh_rms_distance, b.mesh_rms_distance)
                && bits(a.scaled_jacobian_min, b.scaled_jacobian_min)
                && a.sd == b.sd,
            "{}: fit {} / {}, mesh {} / {}, quality {} / {}",
            a.name,
            a.rms_distance,
            b.rms_distance,
            a.mesh_rms_distance,
            b.mesh_rms_distance,
            a.scaled_jacobian_min,
            b.scaled_jacobian_min
        );
    };
    let out = common::temp_dir("hands-k-fold");
    let r = atlasmesh::study::cross_validation(
        atlasmesh::study::Folds::of(&shapes),
        3,
        "imm-hands-2d",
        &params,
        &out,
        0,
        &atlasmesh::study::Silent,
    )
    .unwrap();
    assert_eq!(r.folds, Some(3));
    assert_eq!(r.subjects.len(), 12, "{:?}", r.failed);
    let folds: Vec<Option<usize>> = r.subjects.iter().map(|s| s.fold).collect();
    let expected: Vec<Option<usize>> = (0..12).map(|k| Some(k / 4 + 1)).collect();
    assert_eq!(folds, expected);
    // Every success read back from its file and agreeing with it (fewer training shapes than
    // a leave-one-out's: a hand may miss its bound).
    assert_eq!(
        common::assert_delivered(&r, &out, &shapes),
        r.summary.succeeded
    );
    assert!(r.summary.succeeded >= 10, "{:?}", r.summary);
    let written: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(written["folds"], 3);
    assert_eq!(written["subjects"][5]["fold"], 2);
    let page = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(page.contains("3-fold cross-validation: 12 shapes"));
    // Subject k of fold g against the leave-one-out of the other folds' shapes and k.
    for k in [0, 5, 11] {
        let mut population: Vec<_> = (0..12)
            .filter(|i| i / 4 != k / 4)
            .map(|i| shapes[i].clone())
            .collect();
        population.push(shapes[k].clone());
        let alone = common::temp_dir("hands-k-fold-as-loo");
        let one = leave_one_out(
            &population,
            "imm-hands-2d",
            &params,
            &alone,
            0,
            &atlasmesh::study::Silent,
        )
        .unwrap();
        same(&r.subjects[k], one.subjects.last().unwrap());
        let _ = std::fs::remove_dir_all(&alone);
    }
    // As many folds as shapes: the leave-one-out, its subjects numbered 1 to 12.
    let all = common::temp_dir("hands-12-fold");
    let twelve = atlasmesh::study::cross_validation(
        atlasmesh::study::Folds::of(&shapes),
        12,
        "imm-hands-2d",
        &params,
        &all,
        0,
        &atlasmesh::study::Silent,
    )
    .unwrap();
    let loo = common::temp_dir("hands-12-loo");
    let plain = leave_one_out(
        &shapes,
        "imm-hands-2d",
        &params,
        &loo,
        0,
        &atlasmesh::study::Silent,
    )
    .unwrap();
    assert_eq!(plain.folds, None);
    assert!(plain.subjects.iter().all(|s| s.fold.is_none()));
    for (i, (a, b)) in twelve.subjects.iter().zip(&plain.subjects).enumerate() {
        assert_eq!(a.fold, Some(i + 1));
        same(a, b);
    }
    // Folds that leave too few shapes to an atlas, or too few or too many folds: refused.
    for k in [0, 1, 13] {
        let e = atlasmesh::study::fold_groups(12, k)
            .unwrap_err()
            .to_string();
        assert!(e.contains("between 2 and the number of shapes (12)"), "{e}");
    }
    let e = atlasmesh::study::fold_groups(5, 2).unwrap_err().to_string();
    assert!(e.contains("leave 2 shapes to an atlas"), "{e}");
    for d in [out, all, loo] {
        let _ = std::fs::remove_dir_all(&d);
    }
}

/// `loo --folds 5` on the 40 hands of one CSV: 5 folds of 8 consecutive shapes, each subject's
/// fold in `report.json` and the title of `report.html`; `--folds` of 1 or of more folds than
/// shapes refused with the reason, and nothing written.
#[test]
fn the_command_lines_k_fold_cross_validation() {
    let Some(data) = common::data_dir("the_command_lines_k_fold_cross_validation") else {
        return;
    };
    let csv = data
        .join("imm-hands-2d/hands_long.csv")
        .display()
        .to_string();
    let out = common::temp_dir("hands-cli-k-fold");
    let run = |folds: &str, dir: &std::path::Path| {
        common::atlasmesh(&[
            "loo",
            "--no-plots",
            "--open",
            "--modes",
            "5",
            "--shapes",
            &csv,
            "--folds",
            folds,
            "--out",
            &dir.display().to_string(),
        ])
    };
    let o = run("5", &out.join("five"));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r: atlasmesh::report::Report =
        serde_json::from_slice(&std::fs::read(out.join("five/report.json")).unwrap()).unwrap();
    assert_eq!(r.folds, Some(5));
    assert_eq!(r.subjects.len() + r.failed.len(), 40);
    for s in &r.subjects {
        let k: usize = s.name.parse().unwrap();
        assert_eq!(s.fold, Some(k / 8 + 1), "{}", s.name);
    }
    let page = std::fs::read_to_string(out.join("five/report.html")).unwrap();
    assert!(page.contains("5-fold cross-validation: 40 shapes"));
    // Every success read back from its file (by meshio too) and agreeing with it.
    let hands = common::hands(&data, None);
    assert_eq!(
        common::assert_delivered(&r, &out.join("five"), &hands),
        r.summary.succeeded
    );
    for (folds, why) in [
        ("1", "a whole number from 2"),
        ("41", "between 2 and the number of shapes (40)"),
    ] {
        let dir = out.join(format!("refused-{folds}"));
        let o = run(folds, &dir);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && err.contains(why),
            "--folds {folds}: {err}"
        );
        assert!(!dir.join("report.json").exists());
    }
    let _ = std::fs::remove_dir_all(&out);
}
