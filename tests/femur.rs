//! The paper's femur experiment (section 6.2) on the 30 first distal femurs of
//! `$ATLASMESH_DATA/knee-distal-femur-synthetic-3d`: leave-one-out with an automatic
//! hexahedral mesh of the mean, 15 modes (the model that generated the data) and 5 modes.

mod common;

use atlasmesh::model::ModeSelection;
use atlasmesh::pipeline::{RunParams, leave_one_out, load_surfaces};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

#[test]
fn femur_leave_one_out_with_15_and_5_modes() {
    let Some(data) = common::data_dir("femur_leave_one_out_with_15_and_5_modes") else {
        return;
    };
    let paths: Vec<_> = (1..=30)
        .map(|k| {
            data.join(format!(
                "knee-distal-femur-synthetic-3d/femur/S{k:03}_Femur.ply"
            ))
        })
        .collect();
    let shapes = load_surfaces(&paths).unwrap();
    assert!(shapes.iter().all(|s| s.points.len() == 7313));
    let edge = median(shapes.iter().map(|s| s.median_edge_length()).collect());
    assert!((edge - 1.85).abs() < 0.1, "median edge length {edge} mm");
    let out = common::temp_dir("femur-loo");
    for (modes, bound) in [(15, 0.5 * edge), (5, 0.6)] {
        let mut params = RunParams::default();
        params.atlas.modes = ModeSelection::Count(modes);
        params.atlas.element_size = 0.02; // about 2 mm on a femur 100 mm long
        params.plots = false;
        let r = leave_one_out(&shapes, "femur", &params, &out, 0, true).unwrap();
        assert_eq!(r.dimension, 3);
        assert_eq!(r.summary.subjects, 30);
        assert_eq!(
            r.summary.meshes_valid, 30,
            "{modes} modes: every morphed hex mesh valid"
        );
        assert_eq!(r.summary.succeeded, 30, "{modes} modes: every femur fitted");
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
        // VTU written per subject.
        assert!(out.join("S001_Femur_mesh.vtu").is_file());
    }
    let _ = std::fs::remove_dir_all(&out);
}
