//! `atlasmesh fit --landmarks-only` as users run it, on held-out femurs: an atlas of the
//! femurs S001-S030 built with the 3 landmarks of the registration tests, then each of
//! S031-S040 known only by those 3 landmark positions (Scalismo JSON). The posterior mean is
//! read back by PyVista with its per-point standard deviation and measured against the true
//! femur (the data's vertices correspond): closer than the mean shape placed on the same
//! landmarks, and the 2σ band covering most of the actual errors.

use crate::common::{self, atlasmesh};
use crate::raw_femurs::FEMUR_LANDMARKS;
use std::path::Path;

fn s(p: &Path) -> String {
    p.display().to_string()
}

const NAMES: [&str; 3] = ["epicondyle_lateral", "epicondyle_medial", "shaft"];

#[test]
fn femurs_from_three_landmarks_beat_the_mean_shape() {
    let Some(data) = common::data_dir("femurs_from_three_landmarks_beat_the_mean_shape") else {
        return;
    };
    let d = common::temp_dir("posterior");
    let dir = data.join("knee-distal-femur-synthetic-3d/femur");
    let mut csv = String::from("shape,landmark,index\n");
    let mut shapes = Vec::new();
    for k in 1..=30 {
        for (n, i) in NAMES.iter().zip(FEMUR_LANDMARKS) {
            csv.push_str(&format!("S{k:03}_Femur,{n},{i}\n"));
        }
        shapes.push(s(&dir.join(format!("S{k:03}_Femur.ply"))));
    }
    std::fs::write(d.join("landmarks.csv"), csv).unwrap();
    let atlas = s(&d.join("femur.safetensors"));
    let lm = s(&d.join("landmarks.csv"));
    let mut args = vec![
        "build",
        "--element-size",
        "2%",
        "--landmarks",
        &lm,
        "--out",
        &atlas,
        "--shapes",
    ];
    args.extend(shapes.iter().map(String::as_str));
    let o = atlasmesh(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let model = atlasmesh::model::Atlas::<3>::load(Path::new(&atlas)).unwrap();
    assert_eq!(model.landmark_ids, NAMES.map(String::from).to_vec());
    // The held-out femurs' landmark positions, in their own order (ids pair them).
    let mut files = Vec::new();
    for k in 31..=40 {
        let femur =
            atlasmesh::formats::read_surface(&dir.join(format!("S{k:03}_Femur.ply"))).unwrap();
        let json: Vec<serde_json::Value> = NAMES
            .iter()
            .zip(FEMUR_LANDMARKS)
            .rev()
            .map(|(n, i)| serde_json::json!({"id": n, "coordinates": femur.points[i]}))
            .collect();
        let f = d.join(format!("S{k:03}_Femur.json"));
        std::fs::write(&f, serde_json::to_string(&json).unwrap()).unwrap();
        files.push(s(&f));
    }
    let out = d.join("out");
    let mut args = vec!["fit", "--atlas", &atlas, "--landmarks-only"];
    args.extend(files.iter().map(String::as_str));
    let o_s = s(&out);
    args.extend(["--landmark-sd", "1", "--out", &o_s]);
    let o = atlasmesh(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let report: atlasmesh::report::PosteriorRunReport =
        serde_json::from_slice(&std::fs::read(out.join("posterior.json")).unwrap()).unwrap();
    assert_eq!(report.subjects.len(), 10);
    for r in &report.subjects {
        assert_eq!(r.landmarks.len(), 3, "{}", r.name);
        assert_eq!(r.inverted_elements, 0);
        assert!(r.scaled_jacobian_min >= 0.2, "{}", r.name);
        assert!(
            r.landmark_rms < 1.0,
            "{}: landmarks {} mm off",
            r.name,
            r.landmark_rms
        );
        for f in &r.files {
            assert!(out.join(f).is_file(), "{f}");
        }
    }
    // Read back by PyVista: every femur's error against the truth.
    let Some(py) = common::python() else { return };
    let script = r#"
import sys, json, numpy as np, pyvista as pv
out, data, mean_file = sys.argv[1], sys.argv[2], sys.argv[3]
L = [int(v) for v in sys.argv[4].split(',')]
mean = pv.read(mean_file).points
def place(src, dst):
    ms, md = src.mean(0), dst.mean(0); a, b = src - ms, dst - md
    U, S, Vt = np.linalg.svd(b.T @ a); d = np.sign(np.linalg.det(U @ Vt)); E = np.diag([1, 1, d])
    R = U @ E @ Vt; s = (S * np.diag(E)).sum() / (a ** 2).sum()
    return lambda x: s * (x - ms) @ R.T + md
rows = []
for k in range(31, 41):
    n = 'S%03d_Femur' % k
    truth = pv.read('%s/%s.ply' % (data, n)).points
    fit = pv.read('%s/%s/%s_fit.vtp' % (out, n, n))
    mesh = pv.read('%s/%s/%s_mesh.vtu' % (out, n, n))
    sd = np.asarray(fit.point_data['posterior_sd'])
    e = np.linalg.norm(fit.points - truth, axis=1)
    em = np.linalg.norm(place(mean[L], truth[L])(mean) - truth, axis=1)
    rows.append(dict(name=n, posterior=float(np.sqrt((e ** 2).mean())),
        mean=float(np.sqrt((em ** 2).mean())), sd=float(np.sqrt((sd ** 2).mean())),
        coverage=float((e <= 2 * sd).mean()),
        mesh_sd=int(mesh.point_data['posterior_sd'].shape[0] == mesh.n_points),
        mesh_sd_min=float(mesh.point_data['posterior_sd'].min())))
print(json.dumps(rows))
"#;
    let mean_vtp = d.join("femur_mean.vtp");
    let lms = FEMUR_LANDMARKS.map(|i| i.to_string()).join(",");
    let o = crate::common::run(
        std::process::Command::new(py).args(["-c", script, &o_s, &s(&dir), &s(&mean_vtp), &lms]),
        crate::common::deadline::PYTHON,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows: Vec<serde_json::Value> = serde_json::from_slice(&o.stdout).unwrap();
    let f = |r: &serde_json::Value, k: &str| r[k].as_f64().unwrap();
    let mut coverage = Vec::new();
    for r in &rows {
        eprintln!(
            "{}: posterior mean {:.3} mm (RMS) from the true femur, mean shape {:.3} mm; predicted sd {:.3} mm; 2σ covers {:.1} %",
            r["name"],
            f(r, "posterior"),
            f(r, "mean"),
            f(r, "sd"),
            100.0 * f(r, "coverage")
        );
        assert!(
            f(r, "posterior") < f(r, "mean"),
            "{}: the posterior is no closer than the mean shape",
            r["name"]
        );
        assert_eq!(
            f(r, "mesh_sd"),
            1.0,
            "the mesh carries posterior_sd at every node"
        );
        assert!(f(r, "mesh_sd_min") > 0.0);
        coverage.push(f(r, "coverage"));
    }
    coverage.sort_by(f64::total_cmp);
    assert!(coverage[5] > 0.8, "median 2σ coverage {}", coverage[5]);
}
