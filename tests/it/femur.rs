//! The paper's femur experiment (section 6.2) on the 30 first distal femurs of
//! `$ATLASMESH_DATA/knee-distal-femur-synthetic-3d`: leave-one-out with an automatic
//! hexahedral mesh of the mean, 15 modes (the model that generated the data) and 5 modes.

use crate::common;

use atlasmesh::model::ModeSelection;
use atlasmesh::study::RunParams;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

#[test]
fn femur_leave_one_out_with_15_and_5_modes() {
    let Some(data) = common::data_dir("femur_leave_one_out_with_15_and_5_modes") else {
        return;
    };
    let shapes = common::femurs(&data);
    assert!(shapes.iter().all(|s| s.points.len() == 7313));
    let edge = median(shapes.iter().map(|s| s.median_edge_length()).collect());
    assert!((edge - 1.85).abs() < 0.1, "median edge length {edge} mm");
    let out = common::temp_dir("femur-loo");
    let params = RunParams {
        element_size: atlasmesh::mesh::ElementSize::Share(0.02), // about 2 mm on a femur 100 mm long
        plots: false,
        ..Default::default()
    };
    // Each fold's atlas and mean mesh built once, cut to 15 and to 5 modes.
    let reports = atlasmesh::study::leave_one_out_by_modes(
        atlasmesh::study::Folds::of(&shapes),
        "femur",
        &params,
        &[15, 5],
        &out,
        0,
        &atlasmesh::study::Silent,
    )
    .unwrap();
    for ((modes, bound), r) in [(15, 0.5 * edge), (5, 0.6)].into_iter().zip(reports) {
        let out = out.join(format!("modes-{modes}"));
        assert_eq!(r.modes, modes);
        assert_eq!(r.dimension, 3);
        assert_eq!(r.summary.subjects, 30);
        common::assert_repaired(&format!("femurs, {modes} modes"), &r);
        assert_eq!(
            r.summary.meshes_valid, 30,
            "{modes} modes: every morphed hex mesh valid"
        );
        assert_eq!(r.summary.succeeded, 30, "{modes} modes: every femur fitted");
        assert_eq!(common::assert_delivered(&r, &out, &shapes), 30);
        assert!(
            r.subjects.iter().all(|s| s.converged),
            "{modes} modes: every fit met the tolerance at the last gamma"
        );
        let rms = median(r.subjects.iter().map(|s| s.rms_distance).collect());
        eprintln!("{modes} modes: median two-way RMS {rms:.3} mm (bound {bound:.3})");
        assert!(
            rms <= bound,
            "{modes} modes: median two-way RMS {rms} mm > {bound}"
        );
        let mm = r.mean_mesh.as_ref().unwrap();
        assert_eq!(mm.element_kind, "hex8");
        assert!(
            mm.scaled_jacobian_min >= 0.2,
            "mean hex mesh min SJ {}",
            mm.scaled_jacobian_min
        );
        // No sliver hexahedron in the pillow layer of the mean mesh or of a morphed one
        // (their corners can be square while they are flat).
        let worst = r
            .subjects
            .iter()
            .map(|s| s.edge_ratio_max)
            .fold(0.0, f64::max);
        eprintln!(
            "{modes} modes: largest edge ratio {:.2} (mean mesh), {worst:.2} (morphed)",
            mm.edge_ratio_max
        );
        assert!(
            mm.edge_ratio_max < 5.0,
            "mean mesh edge ratio {}",
            mm.edge_ratio_max
        );
        // Abaqus warns from an aspect ratio of 10 on.
        assert!(worst < 10.0, "morphed mesh edge ratio {worst}");
        // VTU written per subject.
        assert!(out.join("S001_Femur_mesh.vtu").is_file());
    }
    let _ = std::fs::remove_dir_all(&out);
}

/// Incomplete subjects (paper, fig. 21-22): a femur with the 20 % of its vertices farthest
/// along its longest principal axis cut away, fitted with `partial`, gives mode weights
/// (in standard deviations) within 0.5 of the complete femur's fit, for every mode.
#[test]
fn incomplete_femur_gives_the_weights_of_the_complete_one() {
    use atlasmesh::fit::{FitParams, Fitter};
    use atlasmesh::geometry::{ClosestPointIndex, Shape, centroid, sub};
    use atlasmesh::model::{Atlas, AtlasParams};
    let Some(data) = common::data_dir("incomplete_femur_gives_the_weights_of_the_complete_one")
    else {
        return;
    };
    let shapes = common::femurs(&data);
    let atlas = Atlas::build(
        &shapes[5..],
        &AtlasParams {
            modes: ModeSelection::Count(15),
            element_size: 0.05,
            ..AtlasParams::default()
        },
    )
    .unwrap();
    let fitter = Fitter::new(std::sync::Arc::new(atlas.clone()));
    let sigma: Vec<f64> = atlas.eigenvalues.iter().map(|l| l.sqrt()).collect();
    for s in &shapes[..5] {
        // Longest principal axis: power iteration on the covariance.
        let c = centroid(&s.points);
        let mut cov = [[0.0; 3]; 3];
        for p in &s.points {
            let d = sub(*p, c);
            for i in 0..3 {
                for j in 0..3 {
                    cov[i][j] += d[i] * d[j];
                }
            }
        }
        let mut axis = [1.0, 0.3, 0.1];
        for _ in 0..100 {
            let v: [f64; 3] = std::array::from_fn(|i| (0..3).map(|j| cov[i][j] * axis[j]).sum());
            let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            axis = v.map(|x| x / n);
        }
        let along: Vec<f64> = s
            .points
            .iter()
            .map(|p| (0..3).map(|d| (p[d] - c[d]) * axis[d]).sum())
            .collect();
        let mut sorted = along.clone();
        sorted.sort_by(f64::total_cmp);
        let cut = sorted[(0.8 * sorted.len() as f64) as usize];
        let kept: Vec<bool> = along.iter().map(|&a| a < cut).collect();
        let mut new_id = vec![usize::MAX; s.points.len()];
        let mut points = Vec::new();
        for (i, p) in s.points.iter().enumerate() {
            if kept[i] {
                new_id[i] = points.len();
                points.push(*p);
            }
        }
        let facets: Vec<[usize; 3]> = s
            .facets
            .iter()
            .filter(|f| f.iter().all(|&v| kept[v]))
            .map(|f| f.map(|v| new_id[v]))
            .collect();
        let part = Shape {
            name: format!("{}-cut", s.name),
            points,
            facets,
            landmarks: Vec::new(),
        };
        let full = fitter
            .fit(s, &ClosestPointIndex::from_shape(s), &FitParams::default())
            .unwrap();
        let partial = fitter
            .fit(
                &part,
                &ClosestPointIndex::from_shape(&part),
                &FitParams {
                    partial: true,
                    ..FitParams::default()
                },
            )
            .unwrap();
        let worst = full
            .weights
            .iter()
            .zip(&partial.weights)
            .zip(&sigma)
            .map(|((a, b), s)| ((a - b) / s).abs())
            .fold(0.0, f64::max);
        let missing = partial.corresponded.iter().filter(|c| !**c).count();
        eprintln!(
            "{}: largest weight difference {worst:.3} sigma; {missing} of {} model points without a partner",
            s.name,
            partial.corresponded.len()
        );
        assert!(worst <= 0.5, "{}: weights differ by {worst} sigma", s.name);
        assert!(
            missing > 0,
            "the cut part has model points without partners"
        );
        // The morph uses the partnered points only and still gives a valid mesh.
        let morph = atlas
            .morpher(&atlasmesh::ffd::FfdParams::default())
            .unwrap()
            .morph(&partial.correspondence())
            .unwrap();
        let q = atlasmesh::mesh::quality::summarize(&atlasmesh::mesh::quality::mesh_quality(
            &morph.mesh,
        ));
        assert_eq!(
            q.inverted_elements, 0,
            "{}: morph of the partial fit",
            s.name
        );
    }
}

/// Why the FFD baseline's normal correlation (fig. 20) can exceed the SSM fit's: against
/// the true correspondence (the femurs' common numbering), the SSM fit's correspondence is
/// the nearer one, while the FFD registration (3 landmarks) scores a normal correlation
/// above even the truth's: the measure rewards a smooth map whose normals agree with the
/// mean's, not the right partner. Six leave-one-out folds.
#[test]
fn ssm_correspondence_is_nearer_the_truth_than_ffd() {
    use atlasmesh::eval::{normal_correlation, normals_at};
    use atlasmesh::geometry::{ClosestPointIndex, SurfacePoint, dist2};
    use rayon::prelude::*;
    let Some(data) = common::data_dir("ssm_correspondence_is_nearer_the_truth_than_ffd") else {
        return;
    };
    let mut shapes = common::femurs(&data);
    for s in shapes.iter_mut() {
        s.landmarks = common::FEMUR_LANDMARKS.to_vec();
    }
    let rows: Vec<[f64; 5]> = (0..6)
        .into_par_iter()
        .map(|k| {
            let train: Vec<_> = shapes
                .iter()
                .enumerate()
                .filter(|(i, _)| *i != k)
                .map(|(_, s)| s.clone())
                .collect();
            let atlas = atlasmesh::model::Atlas::build(
                &train,
                &atlasmesh::model::AtlasParams {
                    modes: ModeSelection::Count(15),
                    element_size: 0.05,
                    ..Default::default()
                },
            )
            .unwrap();
            let subject = &shapes[k];
            let index = ClosestPointIndex::from_shape(subject);
            let fit = atlasmesh::fit::Fitter::new(std::sync::Arc::new(atlas.clone()))
                .fit(subject, &index, &Default::default())
                .unwrap();
            let mean = atlas.mean_shape();
            let reg = atlasmesh::register::register(
                &mean,
                subject,
                &index,
                &atlasmesh::register::RegisterParams::for_dimension(3),
            )
            .unwrap();
            let error = |c: &[SurfacePoint<3>]| {
                median(
                    c.iter()
                        .zip(&subject.points)
                        .map(|(a, b)| dist2(a.point, *b).sqrt())
                        .collect(),
                )
            };
            let truth: Vec<_> = subject.points.iter().map(|p| index.closest(p)).collect();
            let mn = mean.vertex_normals();
            let nc = |c: &[SurfacePoint<3>]| normal_correlation(&mn, &normals_at(subject, c));
            [
                error(&fit.projected),
                error(&reg.correspondence),
                nc(&fit.projected),
                nc(&reg.correspondence),
                nc(&truth),
            ]
        })
        .collect();
    let mean = |i: usize| rows.iter().map(|r| r[i]).sum::<f64>() / rows.len() as f64;
    eprintln!(
        "median distance to the true partner: SSM {:.3} mm, FFD {:.3} mm; normal correlation: SSM {:.5}, FFD {:.5}, truth {:.5}",
        mean(0),
        mean(1),
        mean(2),
        mean(3),
        mean(4)
    );
    assert!(
        rows.iter().all(|r| r[0] < r[1]),
        "SSM nearer the truth in every fold"
    );
    assert!(
        mean(3) > mean(4),
        "FFD's normal correlation above the truth's"
    );
}

/// A femur given as its mirror image (a left femur for an atlas of right ones) is named as
/// such, whether it is fitted (a warning in its report) or refused (in the error); the femur
/// as given gets no such warning.
#[test]
fn a_mirrored_femur_is_named() {
    use atlasmesh::fit::Fitter;
    use atlasmesh::geometry::Shape;
    use atlasmesh::model::{Atlas, AtlasParams};
    let Some(data) = common::data_dir("a_mirrored_femur_is_named") else {
        return;
    };
    let shapes = common::femurs(&data);
    let atlas = Atlas::build(
        &shapes[1..16],
        &AtlasParams {
            modes: ModeSelection::Count(5),
            element_size: 0.05,
            ..AtlasParams::default()
        },
    )
    .unwrap();
    let params = RunParams {
        plots: false,
        ..RunParams::default()
    };
    let fitter = Fitter::new(std::sync::Arc::new(atlas.clone()));
    let morpher = atlas.morpher(&params.morph).unwrap();
    let given =
        atlasmesh::study::fit_subject(&atlas, &fitter, &morpher, &shapes[0], &params).unwrap();
    assert!(
        given.report.warnings.is_empty(),
        "{:?}",
        given.report.warnings
    );
    let s = &shapes[0];
    let mirror = Shape {
        name: "mirrored".into(),
        points: s.points.iter().map(|p| [-p[0], p[1], p[2]]).collect(),
        facets: s.facets.iter().map(|f| [f[1], f[0], f[2]]).collect(),
        landmarks: s.landmarks.clone(),
    };
    match atlasmesh::study::fit_subject(&atlas, &fitter, &morpher, &mirror, &params) {
        Ok(o) => {
            eprintln!(
                "mirrored femur: RMS {:.3} mm, mirror image {:?}; as given {:.3} mm",
                o.report.rms_distance, o.report.mirrored_rms_distance, given.report.rms_distance
            );
            assert!(
                o.report.warnings.iter().any(|w| w.contains("mirrored")),
                "{:?}",
                o.report.warnings
            );
        }
        Err(e) => {
            eprintln!("mirrored femur refused: {e}");
            assert!(e.to_string().contains("mirrored"), "{e}");
        }
    }
}
