//! The command-line tool: the demo, and clear errors with a non-zero exit on bad input.

use crate::common;

use std::path::Path;
use std::process::{Command, Output};

use common::atlasmesh;

fn assert_clean_error(out: &Output, file: &str, words: &str) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "should fail: {err}");
    assert_eq!(out.status.code(), Some(2), "bad input exits with 2: {err}");
    assert!(!err.contains("panicked"), "panic: {err}");
    assert!(err.contains(file), "message names the file {file}: {err}");
    assert!(err.contains(words), "message says {words:?}: {err}");
}

fn write(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.display().to_string()
}

#[test]
fn demo_writes_meshes_report_and_plots() {
    let d = common::temp_dir("demo");
    let out = d.join("demo");
    let o = crate::common::run(
        Command::new(env!("CARGO_BIN_EXE_atlasmesh"))
            .args(["demo", "--out"])
            .arg(&out),
        crate::common::deadline::ATLASMESH,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(r["summary"]["subjects"], 6);
    assert_eq!(r["summary"]["meshes_valid"], 6);
    assert_eq!(r["summary"]["succeeded"], 6);
    // The schema is the same whether or not a subject failed: `failed` is always there.
    assert_eq!(r["failed"], serde_json::json!([]));
    assert_eq!(r["dimension"], 2);
    for f in [
        "cumulative_variance.png",
        "e_d.png",
        "scaled_jacobians.png",
        "atlas.safetensors",
        "atlas_mean_mesh.vtu",
        "demo-24_mesh.vtu",
        "demo-24.png",
    ] {
        let p = out.join(f);
        assert!(
            p.is_file() && std::fs::metadata(&p).unwrap().len() > 100,
            "{f}"
        );
    }
    // The 3D demo: closed surfaces, automatic hexahedral mesh of the mean, fits and morphs.
    let r3: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("3d/report.json")).unwrap()).unwrap();
    assert_eq!(r3["dimension"], 3);
    assert_eq!(r3["summary"]["subjects"], 6);
    assert_eq!(r3["summary"]["meshes_valid"], 6);
    assert_eq!(r3["summary"]["succeeded"], 6);
    assert_eq!(r3["mean_mesh"]["element_kind"], "hex8");
    assert!(out.join("3d/demo3d-24_mesh.vtu").is_file());
    // The delivered mesh pictured by its distance to the subject, beside the fit's picture,
    // and shown on the subject's page.
    let fit_png = std::fs::read(out.join("3d/demo3d-24_distance.png")).unwrap();
    let mesh_png = std::fs::read(out.join("3d/demo3d-24_mesh_distance.png")).unwrap();
    assert_eq!(&mesh_png[1..4], b"PNG");
    assert!(mesh_png.len() > 10_000 && mesh_png != fit_png);
    let page = std::fs::read_to_string(out.join("3d/demo3d-24.html")).unwrap();
    assert!(page.contains("demo3d-24_mesh_distance.png"));
    let png = std::fs::read(out.join("demo-24.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    // A fit with the saved atlas, through the CLI, of one demo shape written as text.
    let subj = out.join("demo-24_fit.vtp");
    assert!(subj.is_file());
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn build_then_fit_through_the_cli() {
    let d = common::temp_dir("buildfit");
    let mut csv = String::from("shape,point,x,y\n");
    for k in 0..8 {
        for i in 0..60 {
            let t = i as f64 / 60.0 * std::f64::consts::TAU;
            let r = 1.0 + 0.3 * t.cos() + 0.05 * (k as f64) * (2.0 * t).sin();
            csv.push_str(&format!(
                "s{k},{i},{},{}\n",
                r * t.cos() * (1.0 + 0.02 * k as f64),
                r * t.sin()
            ));
        }
    }
    let pop = write(&d, "pop.csv", &csv);
    let atlas = d.join("a.safetensors").display().to_string();
    let o = atlasmesh(&[
        "build",
        "--shapes",
        &pop,
        "--resample",
        "200",
        "--modes",
        "3",
        "--element-size",
        "4%",
        "--out",
        &atlas,
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let subj: String = (0..90)
        .map(|i| {
            let t = i as f64 / 90.0 * std::f64::consts::TAU;
            let r = 1.0 + 0.3 * t.cos() + 0.15 * (2.0 * t).sin();
            format!("{} {}\n", 10.0 * r * t.cos() + 3.0, 10.0 * r * t.sin())
        })
        .collect();
    let s = write(&d, "subject.txt", &subj);
    let out = d.join("fit").display().to_string();
    let o = atlasmesh(&[
        "fit",
        "--atlas",
        &atlas,
        "--subject",
        &s,
        "--out",
        &out,
        "--no-plots",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.join("fit/report.json")).unwrap()).unwrap();
    assert_eq!(r["subjects"][0]["inverted_elements"], 0);
    let rms = r["subjects"][0]["rms_distance"].as_f64().unwrap();
    assert!(r["subjects"][0]["rms_distance_relative"].as_f64().unwrap() < 0.01);

    // The scores and the pose rebuild the fitted instance on the subject: the atlas's
    // S_bar + Psi w (w = sd · sqrt(lambda)) through the pose's 3 × 3 matrix lies on the
    // subject's outline (10 times the population's size, shifted by 3), the bare instance
    // far from it.
    let model = atlasmesh::model::Atlas::<2>::load(Path::new(&atlas)).unwrap();
    let sd: Vec<f64> = r["subjects"][0]["sd"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let w: Vec<f64> = sd
        .iter()
        .zip(&model.eigenvalues)
        .map(|(z, l)| z * l.sqrt())
        .collect();
    let m: Vec<Vec<f64>> =
        serde_json::from_value(r["subjects"][0]["pose"]["matrix"].clone()).unwrap();
    assert_eq!(m[2], vec![0.0, 0.0, 1.0]);
    let outline: Vec<[f64; 2]> = subj
        .lines()
        .map(|l| {
            let v: Vec<f64> = l.split(' ').map(|x| x.parse().unwrap()).collect();
            [v[0], v[1]]
        })
        .collect();
    let to_outline = |p: [f64; 2]| -> f64 {
        (0..outline.len())
            .map(|i| {
                let (a, b) = (outline[i], outline[(i + 1) % outline.len()]);
                let ab = [b[0] - a[0], b[1] - a[1]];
                let t = (((p[0] - a[0]) * ab[0] + (p[1] - a[1]) * ab[1])
                    / (ab[0] * ab[0] + ab[1] * ab[1]))
                    .clamp(0.0, 1.0);
                (p[0] - a[0] - t * ab[0]).hypot(p[1] - a[1] - t * ab[1])
            })
            .fold(f64::INFINITY, f64::min)
    };
    let rms_of = |points: &[[f64; 2]]| -> f64 {
        (points.iter().map(|p| to_outline(*p).powi(2)).sum::<f64>() / points.len() as f64).sqrt()
    };
    let instance = model.instance(&w);
    let posed: Vec<[f64; 2]> = instance
        .iter()
        .map(|p| std::array::from_fn(|r| m[r][0] * p[0] + m[r][1] * p[1] + m[r][2]))
        .collect();
    let (on, bare) = (rms_of(&posed), rms_of(&instance));
    assert!(
        on < 2.0 * rms + 1e-3,
        "posed instance {on} from the outline (fit {rms})"
    );
    assert!(bare > 20.0 * on, "the bare instance {bare}");
    // scores.csv: the same scores, one row per subject.
    let scores = std::fs::read_to_string(d.join("fit/scores.csv")).unwrap();
    let mut lines = scores.lines();
    assert_eq!(lines.next(), Some("name,mode_1,mode_2,mode_3"));
    let row: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(row[0], "subject");
    for (cell, z) in row[1..].iter().zip(&sd) {
        assert_eq!(cell.parse::<f64>().unwrap(), *z);
    }
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn malformed_csv_is_a_clear_error() {
    let d = common::temp_dir("badcsv");
    let f = write(
        &d,
        "bad.csv",
        "shape,point,x,y\n0,0,1.0,2.0\n0,1,abc,2.0\n0,2,1,1\n",
    );
    let o = atlasmesh(&[
        "loo",
        "--shapes",
        &f,
        "--out",
        &d.join("o").display().to_string(),
    ]);
    assert_clean_error(&o, "bad.csv:3", "not a number");
    assert!(!d.join("o/report.json").exists(), "no output on error");
}

#[test]
fn nan_coordinate_is_a_clear_error() {
    let d = common::temp_dir("nan");
    let f = write(&d, "nan.txt", "0 0\n1 0\nNaN 1\n0 1\n");
    let o = atlasmesh(&[
        "loo",
        "--shapes",
        &f,
        "--out",
        &d.join("o").display().to_string(),
    ]);
    assert_clean_error(&o, "nan.txt:3", "NaN");
}

#[test]
fn too_few_points_is_a_clear_error() {
    let d = common::temp_dir("few");
    let f = write(&d, "two.txt", "0 0\n1 0\n");
    let o = atlasmesh(&[
        "loo",
        "--shapes",
        &f,
        "--out",
        &d.join("o").display().to_string(),
    ]);
    assert_clean_error(&o, "two.txt", "at least 3");
}

#[test]
fn different_point_counts_without_resample_is_a_clear_error() {
    let d = common::temp_dir("counts");
    let a = write(&d, "a.txt", "0 0\n1 0\n1 1\n0 1\n");
    let b = write(&d, "b.txt", "0 0\n1 0\n1 1\n0.5 1.5\n0 1\n");
    let o = atlasmesh(&[
        "loo",
        "--shapes",
        &a,
        &b,
        "--out",
        &d.join("o").display().to_string(),
    ]);
    assert_clean_error(&o, "b.txt", "--resample");
}

#[test]
fn a_3d_vtk_given_as_outline_is_a_clear_error() {
    let d = common::temp_dir("dim");
    let f = write(
        &d,
        "tri.vtk",
        "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0 0 0 1 0 1 0 1 2\nLINES 1 4\n3 0 1 2\n",
    );
    let o = atlasmesh(&[
        "loo",
        "--shapes",
        &f,
        "--out",
        &d.join("o").display().to_string(),
    ]);
    assert_clean_error(&o, "tri.vtk", "3D");
}

#[test]
fn missing_file_is_an_io_error() {
    let o = atlasmesh(&[
        "loo",
        "--shapes",
        "/nonexistent/hands.csv",
        "--out",
        "/tmp/x",
    ]);
    assert_eq!(o.status.code(), Some(3));
    assert!(String::from_utf8_lossy(&o.stderr).contains("/nonexistent/hands.csv"));
}

/// Bad 3D surfaces: each gets exit code 2 and a message naming the file and the problem.
#[test]
fn bad_surfaces_are_clear_errors() {
    let d = common::temp_dir("bad3d");
    let tetra_ply = |vertices: &str, body: &str| {
        format!(
            "ply\nformat ascii 1.0\nelement vertex {vertices}\nproperty float x\nproperty float y\nproperty float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n{body}"
        )
    };
    let good_body = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n";
    let nan_body = "0 0 0\n1 0 0\nnan 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n";
    // A Möbius strip cannot be oriented.
    let mut mobius = String::new();
    let n = 12;
    for i in 0..n {
        let t = i as f64 / n as f64 * std::f64::consts::TAU;
        for s in [-0.3, 0.3] {
            let (x, y, z) = (
                (1.0 + s * (t / 2.0).cos()) * t.cos(),
                (1.0 + s * (t / 2.0).cos()) * t.sin(),
                s * (t / 2.0).sin(),
            );
            mobius.push_str(&format!("v {x} {y} {z}\n"));
        }
    }
    for i in 0..n {
        let (a, b) = (2 * i + 1, 2 * i + 2);
        let (c, e) = if i + 1 < n {
            (2 * i + 3, 2 * i + 4)
        } else {
            (2, 1) // the half twist: the strip's edges swap
        };
        mobius.push_str(&format!("f {a} {b} {e}\nf {a} {e} {c}\n"));
    }
    let cases: Vec<(String, &str)> = vec![
        (write(&d, "empty.ply", ""), "end_header"),
        (
            write(&d, "lies.ply", &tetra_ply("40", good_body)),
            "truncated",
        ),
        (write(&d, "nan.ply", &tetra_ply("4", nan_body)), "NaN"),
        (write(&d, "mobius.obj", &mobius), "cannot be oriented"),
        (write(&d, "notstl.stl", "hello"), "solid"),
    ];
    for (f, words) in &cases {
        let o = atlasmesh(&[
            "loo",
            "--shapes",
            f,
            f,
            f,
            f,
            "--out",
            &d.join("o").display().to_string(),
        ]);
        let name = std::path::Path::new(f)
            .file_name()
            .unwrap()
            .to_string_lossy()
            .to_string();
        assert_clean_error(&o, &name, words);
    }
    // 2D and 3D mixed.
    let ply = write(&d, "t.ply", &tetra_ply("4", good_body));
    let txt = write(&d, "o.txt", "0 0\n1 0\n1 1\n0 1\n");
    let o = atlasmesh(&[
        "loo",
        "--shapes",
        &ply,
        &txt,
        "--out",
        &d.join("o").display().to_string(),
    ]);
    assert_clean_error(&o, "o.txt", "2D and 3D shapes mixed");
    assert!(!d.join("o/report.json").exists(), "no output on error");
    std::fs::remove_dir_all(&d).ok();
}

/// Landmark files that do not fit the population, and a target that the ICP cannot align:
/// clear errors naming the file or the shapes, exit code 2, no atlas written.
#[test]
fn bad_landmarks_and_unalignable_targets_are_clear_errors() {
    let d = common::temp_dir("badlm");
    // Four ellipses of 40 points, no correspondence needed (they are registered).
    let ellipse = |a: f64, b: f64| -> String {
        (0..40)
            .map(|i| {
                let t = i as f64 / 40.0 * std::f64::consts::TAU;
                format!("{} {}\n", a * t.cos(), b * t.sin())
            })
            .collect()
    };
    let shapes: Vec<String> = [(2.0, 1.0), (2.2, 1.0), (1.8, 1.1), (2.0, 0.9)]
        .iter()
        .enumerate()
        .map(|(k, (a, b))| write(&d, &format!("s{k}.txt"), &ellipse(*a, *b)))
        .collect();
    let out = d.join("atlas.safetensors");
    let build = |extra: &[&str]| {
        let mut args = vec!["build", "--register", "--closed", "--shapes"];
        args.extend(shapes.iter().map(String::as_str));
        args.extend_from_slice(extra);
        args.extend_from_slice(&["--out", out.to_str().unwrap()]);
        atlasmesh(&args)
    };
    let rows = |f: &dyn Fn(usize) -> String| -> String {
        let mut s = String::from("shape,landmark,index\n");
        for k in 0..4 {
            s.push_str(&f(k));
        }
        s
    };
    let ghost = write(
        &d,
        "ghost.csv",
        &(rows(&|k| format!("s{k},0,0\ns{k},1,10\n")) + "ghost,0,3\nghost,1,5\n"),
    );
    assert_clean_error(&build(&["--landmarks", &ghost]), "ghost.csv", "'ghost'");
    let counts = write(
        &d,
        "counts.csv",
        &rows(&|k| {
            if k == 2 {
                format!("s{k},0,0\n")
            } else {
                format!("s{k},0,0\ns{k},1,10\n")
            }
        }),
    );
    // Landmarks are paired by id: a shape without landmark 1 leaves it unused by every
    // shape, with a warning naming the shapes and the file (the others are still used).
    let o = build(&["--landmarks", &counts]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let facts = std::fs::read_to_string(d.join("atlas.inputs.json")).unwrap();
    assert!(
        facts.contains("landmark(s) [1] of") && facts.contains("counts.csv"),
        "{facts}"
    );
    std::fs::remove_file(&out).ok();
    // No landmark in common.
    let none = write(&d, "none.csv", &rows(&|k| format!("s{k},{k},0\n")));
    assert_clean_error(
        &build(&["--landmarks", &none]),
        "none.csv",
        "no landmark id is in every shape",
    );
    let range = write(
        &d,
        "range.csv",
        &rows(&|k| format!("s{k},0,0\ns{k},1,{}\n", if k == 1 { 40 } else { 10 })),
    );
    assert_clean_error(
        &build(&["--landmarks", &range]),
        "range.csv",
        "out of range",
    );
    // A landmark given by coordinates far away from its shape (another shape's file?).
    let far: Vec<String> = (0..4)
        .map(|k| {
            let x = if k == 3 { 500.0 } else { 2.0 };
            write(
                &d,
                &format!("l{k}.json"),
                &format!(
                    r#"[{{"id":"a","coordinates":[{x},0.0]}},{{"id":"b","coordinates":[-2.0,0.0]}}]"#
                ),
            )
        })
        .collect();
    let mut args = vec!["--landmarks"];
    args.extend(far.iter().map(String::as_str));
    assert_clean_error(&build(&args), "l3.json", "far from");
    // A target the ICP cannot align: no extent (40 points within 1e-13 of each other).
    let speck: String = (0..40)
        .map(|i| {
            format!(
                "{} {}\n",
                1.0 + 1e-13 * (i % 3) as f64,
                1.0 + 1e-13 * (i % 5) as f64
            )
        })
        .collect();
    let z = write(&d, "speck.txt", &speck);
    let o = atlasmesh(&[
        "register",
        "--template",
        &shapes[0],
        "--target",
        &z,
        "--out",
        d.join("reg").to_str().unwrap(),
    ]);
    assert_clean_error(&o, "speck", "could not align");
    assert!(!out.exists(), "no atlas written after an error");
    assert!(!d.join("reg").join("registration.json").exists());
}

const CUBE_INP: &str = "*NODE
1, 0, 0, 0
2, 1, 0, 0
3, 1, 1, 0
4, 0, 1, 0
5, 0, 0, 1
6, 1, 0, 1
7, 1, 1, 1
8, 0, 1, 1
*ELEMENT, TYPE=C3D8, ELSET=ALL
1, 1, 2, 3, 4, 5, 6, 7, 8
*NSET, NSET=BOTTOM
1, 2, 3, 4
*SURFACE, NAME=TOP, TYPE=ELEMENT
1, S2
";

/// `atlasmesh quality` and `convert` on a one-cube mesh; bad FE meshes and sets configs are
/// clear errors (exit 2), an inverted mesh exits with 4.
#[test]
fn quality_convert_and_bad_fe_meshes() {
    let d = common::temp_dir("femesh");
    let cube = write(&d, "cube.inp", CUBE_INP);
    let o = atlasmesh(&["quality", &cube, "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let q: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(q["elements"], 1);
    assert!((q["scaled_jacobian_min"].as_f64().unwrap() - 1.0).abs() < 1e-12);
    assert_eq!(q["elements_below_bound"], 0);
    // Converted to every format and back: the same mesh and sets.
    for ext in ["msh", "vtu", "vtk", "inp"] {
        let p = d.join(format!("c.{ext}")).display().to_string();
        let o = atlasmesh(&["convert", &cube, &p]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let m: atlasmesh::mesh::FeMesh<3> =
            atlasmesh::formats::read_fe_mesh(std::path::Path::new(&p)).unwrap();
        assert_eq!(m.sets.node_sets["BOTTOM"], vec![0, 1, 2, 3], "{ext}");
        assert_eq!(m.sets.element_sets["ALL"], vec![0], "{ext}");
    }
    // Inverted: top and bottom swapped.
    let inverted = write(
        &d,
        "inverted.inp",
        &CUBE_INP.replace("1, 1, 2, 3, 4, 5, 6, 7, 8", "1, 5, 6, 7, 8, 1, 2, 3, 4"),
    );
    let o = atlasmesh(&["quality", &inverted]);
    assert_eq!(
        o.status.code(),
        Some(4),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains("inverted"));
    // Bad inputs.
    let unknown = write(&d, "beam.inp", &CUBE_INP.replace("C3D8", "B31"));
    assert_clean_error(&atlasmesh(&["quality", &unknown]), "beam.inp", "B31");
    let missing = write(
        &d,
        "missing.inp",
        &CUBE_INP.replace("1, 2, 3, 4\n*SURFACE", "1, 2, 3, 44\n*SURFACE"),
    );
    assert_clean_error(&atlasmesh(&["quality", &missing]), "missing.inp", "44");
    let msh = d.join("c.msh");
    let full = std::fs::read_to_string(&msh).unwrap();
    let cut = write(&d, "cut.msh", &full[..full.len() * 2 / 3]);
    assert_clean_error(&atlasmesh(&["quality", &cut]), "cut.msh", "truncated");
    let nothing = write(
        &d,
        "nothing.toml",
        "[[node_set]]\nname = \"FAR\"\nbox = { min = [2, 2, 2], max = [3, 3, 3] }\n",
    );
    let out = d.join("o.inp").display().to_string();
    assert_clean_error(
        &atlasmesh(&["convert", &cube, &out, "--sets", &nothing]),
        "nothing.toml",
        "selects no node",
    );
    assert!(
        !std::path::Path::new(&out).exists(),
        "no output after an error"
    );
    let typo = write(&d, "typo.toml", "[[node_set]]\nname = \"A\"\nbx = 1\n");
    assert_clean_error(
        &atlasmesh(&["convert", &cube, &out, "--sets", &typo]),
        "typo.toml",
        "bx",
    );
}

/// `atlasmesh repair`: a block of 3 × 3 × 3 hexahedra whose middle node was pushed through
/// the face below it comes out valid, with every scaled Jacobian at least 0.2.
#[test]
fn repair_command_untangles_a_folded_block() {
    let d = common::temp_dir("repair");
    let mut block = atlasmesh::mesh::FeMesh::block(3);
    // Node (1, 1, 2) pushed down through the face below it.
    block.nodes[1 + 4 * (1 + 4 * 2)][2] -= 1.7;
    let folded = d.join("folded.inp");
    let q = atlasmesh::mesh::quality::mesh_quality(&block);
    atlasmesh::formats::write_mesh(&folded, &block, None, &q).unwrap();
    let folded = folded.display().to_string();
    assert_eq!(atlasmesh(&["quality", &folded]).status.code(), Some(4));
    let fixed = d.join("fixed.vtu").display().to_string();
    let o = atlasmesh(&["repair", &folded, "--out", &fixed]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = atlasmesh(&["quality", &fixed, "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let q: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(q["inverted_elements"], 0);
    assert!(q["scaled_jacobian_min"].as_f64().unwrap() >= 0.2, "{q}");
}

/// More shapes than coordinates (120 outlines of 8 points: 16 coordinates), as with hundreds
/// of hearts or molars of few landmarks: the atlas is built, with at most 16 modes.
#[test]
fn an_atlas_of_more_shapes_than_coordinates() {
    let d = common::temp_dir("many-shapes");
    let mut csv = String::from("shape,point,x,y\n");
    for k in 0..120 {
        for i in 0..8 {
            let a = i as f64 * std::f64::consts::TAU / 8.0;
            // A pseudo-random radius per shape and point (full rank).
            let h = ((k * 8 + i) * 2_654_435_761_usize) % 1000;
            let r = 1.0 + 0.15 * (h as f64 / 1000.0 - 0.5);
            csv.push_str(&format!("{k},{i},{},{}\n", r * a.cos(), 0.7 * r * a.sin()));
        }
    }
    let f = write(&d, "many.csv", &csv);
    let atlas = d.join("many.safetensors");
    let o = atlasmesh(&[
        "build",
        "--shapes",
        &f,
        "--variance",
        "0.999",
        "--out",
        &atlas.display().to_string(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let a = atlasmesh::model::Atlas::<2>::load(&atlas).unwrap();
    assert!(
        a.num_modes() >= 5 && a.num_modes() <= 16,
        "{} modes",
        a.num_modes()
    );
    assert!(a.eigenvalues.iter().all(|&l| l > 0.0));
    std::fs::remove_dir_all(&d).ok();
}

/// `convert ATLAS` writes the mean mesh in the data's unit and pose: its extent is the
/// population's (not the reference frame's largest side of 1), and it lies where the shapes
/// lie; an atlas of format version 2 (no data frame) still converts, in the reference frame.
#[test]
fn convert_gives_the_mean_mesh_in_the_data_unit() {
    let d = common::temp_dir("cli-convert-unit");
    let atlas = crate::bad_input::atlas_2d(&d);
    let pop = atlasmesh::study::demo_population(12, 120, 5);
    let extent = |pts: &[[f64; 2]]| {
        let (lo, hi) = atlasmesh::geometry::bounding_box(pts);
        (
            (hi[0] - lo[0]).max(hi[1] - lo[1]),
            [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0],
        )
    };
    let sizes: Vec<f64> = pop.iter().map(|s| extent(&s.points).0).collect();
    let size = sizes.iter().sum::<f64>() / sizes.len() as f64;
    let centre = pop
        .iter()
        .map(|s| extent(&s.points).1)
        .fold([0.0; 2], |a, c| {
            [
                a[0] + c[0] / pop.len() as f64,
                a[1] + c[1] / pop.len() as f64,
            ]
        });
    let out = d.join("mean.vtu");
    let o = atlasmesh(&[
        "convert",
        &atlas.display().to_string(),
        &out.display().to_string(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let m: atlasmesh::mesh::FeMesh<2> = atlasmesh::formats::read_fe_mesh(&out).unwrap();
    let (e, c) = extent(&m.nodes);
    assert!(
        (e / size - 1.0).abs() < 0.05,
        "mean mesh extent {e}, the shapes' {size}"
    );
    assert!(
        atlasmesh::geometry::dist2(c, centre).sqrt() < 0.05 * size,
        "centre {c:?}, the shapes' {centre:?}"
    );
    // An atlas of format version 2.
    let mut a = atlasmesh::model::Atlas::<2>::load(&atlas).unwrap();
    a.data_frame = None;
    let old = d.join("v2.safetensors");
    a.save(&old).unwrap();
    let out2 = d.join("mean2.vtu");
    let o = atlasmesh(&[
        "convert",
        &old.display().to_string(),
        &out2.display().to_string(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let m2: atlasmesh::mesh::FeMesh<2> = atlasmesh::formats::read_fe_mesh(&out2).unwrap();
    for (p, q) in m2.nodes.iter().zip(&a.mesh.nodes) {
        assert!(atlasmesh::geometry::dist2(*p, *q).sqrt() < 1e-9);
    }
}

#[test]
fn options_a_landmarks_only_fit_does_not_use_are_refused() {
    for flag in ["--partial", "--one-way", "--baselines"] {
        let o = crate::common::atlasmesh(&[
            "fit",
            "--atlas",
            "a.safetensors",
            "--landmarks-only",
            "l.json",
            flag,
            "--out",
            "o",
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{flag}: {err}");
        assert!(
            err.contains("cannot be used with") && err.contains(flag),
            "{err}"
        );
    }
    let o = crate::common::atlasmesh(&[
        "fit",
        "--atlas",
        "a.safetensors",
        "--landmarks-only",
        "l.json",
        "--max-misfit",
        "0.1",
        "--out",
        "o",
    ]);
    assert_eq!(o.status.code(), Some(2));
}

/// `build` fits nobody: the options of a subject's fit, morph and outputs are refused by
/// name (exit 2, no atlas written) instead of being ignored; the ones it uses (`--sets`,
/// `--no-plots`) and a fit option given as its default are not.
#[test]
fn build_refuses_the_options_of_a_fit() {
    let d = common::temp_dir("build-fit-options");
    let shapes: Vec<String> = [(2.0, 1.0), (2.2, 1.0), (1.8, 1.1), (2.0, 0.9)]
        .iter()
        .enumerate()
        .map(|(k, (a, b))| {
            let text: String = (0..40)
                .map(|i| {
                    let t = f64::from(i) / 40.0 * std::f64::consts::TAU;
                    format!("{} {}\n", a * t.cos(), b * t.sin())
                })
                .collect();
            write(&d, &format!("s{k}.txt"), &text)
        })
        .collect();
    let out = d.join("atlas.safetensors");
    let build = |extra: &[&str]| {
        let mut args = vec!["build", "--closed", "--shapes"];
        args.extend(shapes.iter().map(String::as_str));
        args.extend_from_slice(extra);
        args.extend_from_slice(&["--out", out.to_str().unwrap()]);
        atlasmesh(&args)
    };
    let o = build(&["--format", "inp", "--partial", "--alpha", "7"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    for flag in ["--format", "--partial", "--alpha", "atlasmesh convert"] {
        assert!(err.contains(flag), "{flag}: {err}");
    }
    assert!(!out.exists());
    let o = build(&["--no-plots", "--alpha", "50"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.is_file());
}
