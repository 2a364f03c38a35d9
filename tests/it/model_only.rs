//! `atlasmesh build --no-mesh`: the shape model alone, from 3D point sets in correspondence
//! without faces; its compactness against a NumPy PCA of the same aligned points; the model
//! file read back, its instances written as point sets, and `fit` refusing it with a reason.

use crate::bad_input::fails;
use crate::common::{self, atlasmesh};
use std::path::Path;

fn s(p: &Path) -> String {
    p.display().to_string()
}

/// A PLY file of vertices only.
fn write_points(path: &Path, points: &[[f64; 3]]) {
    let mut t = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty double x\nproperty double y\nproperty double z\nend_header\n",
        points.len()
    );
    for p in points {
        t.push_str(&format!("{:.17e} {:.17e} {:.17e}\n", p[0], p[1], p[2]));
    }
    std::fs::write(path, t).unwrap();
}

#[test]
fn a_model_of_point_sets_without_a_mesh_matches_numpy_pca() {
    let d = common::temp_dir("model-only");
    // 12 point sets in correspondence: the demo's 3D shapes' vertices, no faces.
    let shapes = atlasmesh::study::demo_population_3d(12, 10, 4).unwrap();
    let mut files = Vec::new();
    for sh in &shapes {
        let f = d.join(format!("{}.ply", sh.name));
        write_points(&f, &sh.points);
        files.push(s(&f));
    }
    let atlas = d.join("model.safetensors");
    let mut args = vec!["build", "--no-mesh", "--measures", "--out"];
    let a = s(&atlas);
    args.push(&a);
    args.push("--shapes");
    args.extend(files.iter().map(String::as_str));
    let o = atlasmesh(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains("no mean mesh"));
    let model = atlasmesh::model::Atlas::<3>::load(&atlas).unwrap();
    assert!(!model.has_mesh() && model.facets.is_empty());
    assert_eq!(model.mean.len(), shapes[0].points.len());
    assert_matches_numpy_pca(&d, &atlas, &shapes);
    // Instances of a model without a mesh: the point sets alone, at the data's size.
    let out = d.join("inst");
    let o = atlasmesh(&[
        "sample",
        "--atlas",
        &a,
        "--n",
        "3",
        "--seed",
        "2",
        "--out",
        &s(&out),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r: atlasmesh::report::InstancesReport =
        serde_json::from_slice(&std::fs::read(out.join("instances.json")).unwrap()).unwrap();
    assert_eq!(r.instances.len(), 3);
    for i in &r.instances {
        assert_eq!(i.elements, 0);
        assert_eq!(i.files, vec![format!("{0}/{0}.vtp", i.name)]);
        let v = atlasmesh::formats::read_vtp(&out.join(&i.files[0])).unwrap();
        assert_eq!(v.points.len(), model.mean.len());
    }
    // fit needs a mesh: refused with the reason, nothing written.
    let fit_out = d.join("fit");
    fails(
        &atlasmesh(&[
            "fit",
            "--atlas",
            &a,
            "--subject",
            &files[0],
            "--out",
            &s(&fit_out),
        ]),
        2,
        &["without a mean mesh", "--no-mesh"],
    );
    assert!(!fit_out.join("report.json").exists());
    // Nor is there a mean mesh to convert.
    let vtu = d.join("mean.vtu");
    fails(
        &atlasmesh(&["convert", &a, &s(&vtu)]),
        2,
        &["has no mesh", "--no-mesh"],
    );
    assert!(!vtu.exists());
}

/// The model in `atlas` (built with `--measures`) against NumPy's PCA of the same aligned
/// points (GPA with tangent projection of `shapes`): compactness and cumulative variance
/// within 1e-9 (when a Python with NumPy is there).
fn assert_matches_numpy_pca(d: &Path, atlas: &Path, shapes: &[atlasmesh::geometry::Shape<3>]) {
    let model = atlasmesh::model::Atlas::<3>::load(atlas).unwrap();
    let measures_file = atlas.with_extension("measures.json");
    let measures: atlasmesh::eval::ShapeModelMeasures =
        serde_json::from_slice(&std::fs::read(&measures_file).unwrap()).unwrap();
    // The same aligned points (GPA with tangent projection) through NumPy's SVD.
    let gpa = atlasmesh::model::generalized_procrustes(
        &shapes.iter().map(|s| s.points.clone()).collect::<Vec<_>>(),
    )
    .unwrap();
    // The first row is the Procrustes mean S_bar: the PCA of section 2.3 is of
    // Phi = [S_k - S_bar] (the mean of the tangent projections differs from S_bar slightly).
    let mut text = String::new();
    for a in std::iter::once(&gpa.mean).chain(&gpa.aligned) {
        let row: Vec<String> = a.iter().flatten().map(|v| format!("{v:.17e}")).collect();
        text.push_str(&row.join(" "));
        text.push('\n');
    }
    let aligned = d.join(format!("aligned-{}.txt", stem(atlas)));
    std::fs::write(&aligned, text).unwrap();
    if let Some(py) = common::python() {
        let script = "import sys, numpy as np\n\
A = np.loadtxt(sys.argv[1])\n\
mean, X = A[0], A[1:]\n\
s = np.linalg.svd(X - mean, compute_uv=False)\n\
l = s**2 / (X.shape[0] - 1)\n\
print(' '.join(repr(float(v)) for v in np.cumsum(l) / l.sum()))\n";
        let o = crate::common::run(
            std::process::Command::new(py).args(["-c", script, &s(&aligned)]),
            crate::common::deadline::PYTHON,
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let numpy: Vec<f64> = String::from_utf8_lossy(&o.stdout)
            .split_whitespace()
            .map(|v| v.parse().unwrap())
            .collect();
        assert!(!measures.compactness.is_empty());
        for (k, c) in measures.compactness.iter().enumerate() {
            assert!(
                (c - numpy[k]).abs() < 1e-9,
                "{} modes: compactness {c}, NumPy {}",
                k + 1,
                numpy[k]
            );
        }
        for (k, c) in model.cumulative_variance.iter().enumerate() {
            assert!(
                (c - numpy[k]).abs() < 1e-9,
                "cumulative variance of mode {}",
                k + 1
            );
        }
    }
}

fn stem(p: &Path) -> String {
    p.file_stem().unwrap().to_string_lossy().into_owned()
}

/// `atlasmesh build --no-mesh --measures` of `files` into `atlas`.
fn build_model(atlas: &Path, files: &[String]) {
    let a = s(atlas);
    let mut args = vec!["build", "--no-mesh", "--measures", "--out", &a, "--shapes"];
    args.extend(files.iter().map(String::as_str));
    let o = atlasmesh(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains("no mean mesh"));
}

#[test]
fn a_model_of_3d_points_from_csv_matches_numpy_pca() {
    let d = common::temp_dir("model-csv");
    let shapes = atlasmesh::study::demo_population_3d(12, 10, 4).unwrap();
    let row = |p: &[f64; 3]| format!("{:.17e},{:.17e},{:.17e}", p[0], p[1], p[2]);
    // One long CSV of every shape (shape,point,x,y,z), as R or pandas write it.
    let mut long = String::from("shape,point,x,y,z\n");
    for sh in &shapes {
        for (k, p) in sh.points.iter().enumerate() {
            long.push_str(&format!("{},{k},{}\n", sh.name, row(p)));
        }
    }
    let long_file = d.join("population.csv");
    std::fs::write(&long_file, long).unwrap();
    let atlas = d.join("long.safetensors");
    build_model(&atlas, &[s(&long_file)]);
    assert_matches_numpy_pca(&d, &atlas, &shapes);
    // A folder of one CSV per shape: x,y,z rows under NumPy's `# x,y,z` header, a plain
    // header, or none at all.
    let folder = d.join("per-shape");
    std::fs::create_dir_all(&folder).unwrap();
    for (k, sh) in shapes.iter().enumerate() {
        let header = ["# x,y,z\n", "x,y,z\n", ""][k % 3];
        let rows: Vec<String> = sh.points.iter().map(row).collect();
        std::fs::write(
            folder.join(format!("{}.csv", sh.name)),
            format!("{header}{}\n", rows.join("\n")),
        )
        .unwrap();
    }
    let atlas = d.join("folder.safetensors");
    build_model(&atlas, &[s(&folder)]);
    // The folder's shapes sorted by name, as the demo's are.
    let mut sorted = shapes.clone();
    sorted.sort_by(|a, b| a.name.cmp(&b.name));
    assert_matches_numpy_pca(&d, &atlas, &sorted);
    // A 2D outline among 3D points is named as such.
    let outline = d.join("outline.csv");
    std::fs::write(&outline, "shape,point,x,y\na,0,0,0\na,1,1,0\na,2,0,1\n").unwrap();
    fails(
        &atlasmesh(&[
            "build",
            "--no-mesh",
            "--out",
            &s(&d.join("mixed.safetensors")),
            "--shapes",
            &s(&long_file),
            &s(&outline),
        ]),
        2,
        &["outline.csv", "2D outline", "3D"],
    );
    // 3D points need --no-mesh: a mesh of the mean needs surfaces.
    fails(
        &atlasmesh(&[
            "build",
            "--out",
            &s(&d.join("meshed.safetensors")),
            "--shapes",
            &s(&long_file),
        ]),
        2,
        &["population.csv", "--no-mesh"],
    );
}
