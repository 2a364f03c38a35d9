//! The bad-input table of the README (issue 8), one test per row, through the command line as
//! a user meets it: the exit code of the error's class, a message that names the file (or
//! shape) and the problem, no panic, and no output file left behind.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use common::atlasmesh;

fn s(p: &Path) -> String {
    p.display().to_string()
}

/// Asserts a clean failure: `code`, every word of `words` in the message, no panic.
pub(crate) fn fails(o: &Output, code: i32, words: &[&str]) {
    let err = String::from_utf8_lossy(&o.stderr);
    eprintln!("exit {:?}: {}", o.status.code(), err.trim());
    assert_eq!(o.status.code(), Some(code), "exit code; stderr: {err}");
    assert!(!err.contains("panicked"), "panic: {err}");
    for w in words {
        assert!(err.contains(w), "message lacks {w:?}: {err}");
    }
}

/// Files under `dir` whose names do not start with a dot.
pub(crate) fn files_in(dir: &Path) -> Vec<PathBuf> {
    let mut v = Vec::new();
    if let Ok(r) = std::fs::read_dir(dir) {
        for e in r.flatten() {
            let p = e.path();
            if p.is_dir() {
                v.extend(files_in(&p));
            } else {
                v.push(p);
            }
        }
    }
    v
}

const TET_PLY_HEADER: &str = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n";
const TET_BODY: &str = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";

/// `loo` on the given shape files (the usual first command), expecting failure.
fn loo(d: &Path, shapes: &[&str]) -> Output {
    let out = d.join("out");
    let mut a = vec!["loo", "--shapes"];
    a.extend_from_slice(shapes);
    let o = s(&out);
    a.extend(["--no-plots", "--out", &o]);
    let r = atlasmesh(&a);
    assert!(
        files_in(&out).is_empty(),
        "output written despite the error: {:?}",
        files_in(&out)
    );
    r
}

/// A binary PLY of the demo's first synthetic surface.
fn binary_ply(d: &Path) -> PathBuf {
    let shape = &atlasmesh::study::demo_population_3d(1, 8, 1).unwrap()[0];
    let p = d.join("good.ply");
    atlasmesh::formats::write_ply(&p, shape).unwrap();
    p
}

#[test]
fn truncated_binary_ply() {
    let d = common::temp_dir("bad-truncated-ply");
    let good = std::fs::read(binary_ply(&d)).unwrap();
    let p = d.join("cut.ply");
    std::fs::write(&p, &good[..good.len() * 2 / 3]).unwrap();
    fails(&loo(&d, &[&s(&p)]), 2, &["cut.ply", "truncated"]);
}

#[test]
fn truncated_binary_stl() {
    let d = common::temp_dir("bad-truncated-stl");
    let shape = &atlasmesh::study::demo_population_3d(1, 8, 1).unwrap()[0];
    let p = d.join("cut.stl");
    atlasmesh::formats::write_stl(&p, shape).unwrap();
    let b = std::fs::read(&p).unwrap();
    std::fs::write(&p, &b[..b.len() - 30]).unwrap();
    fails(&loo(&d, &[&s(&p)]), 2, &["cut.stl"]);
}

#[test]
fn header_counts_that_lie() {
    let d = common::temp_dir("bad-lying-header");
    // PLY: 6 faces announced, 4 present.
    let p = d.join("lies.ply");
    std::fs::write(
        &p,
        TET_PLY_HEADER.replace("element face 4", "element face 6") + TET_BODY,
    )
    .unwrap();
    fails(&loo(&d, &[&s(&p)]), 2, &["lies.ply"]);
    // Legacy VTK: 9 points announced, 4 given.
    let v = d.join("lies.vtk");
    std::fs::write(&v, "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 9 float\n0 0 0 1 0 0 0 1 0 0 0 1\nPOLYGONS 4 16\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n").unwrap();
    fails(&loo(&d, &[&s(&v)]), 2, &["lies.vtk"]);
}

#[test]
fn a_huge_count_in_a_header_allocates_nothing() {
    let d = common::temp_dir("bad-huge-count");
    let p = d.join("huge.ply");
    std::fs::write(
        &p,
        TET_PLY_HEADER.replace("element vertex 4", "element vertex 4000000000") + TET_BODY,
    )
    .unwrap();
    fails(&loo(&d, &[&s(&p)]), 2, &["huge.ply"]);
    // A binary STL claiming 2^32 - 1 triangles in 84 bytes.
    let mut stl = vec![0u8; 84];
    stl[80..84].copy_from_slice(&u32::MAX.to_le_bytes());
    let q = d.join("huge.stl");
    std::fs::write(&q, &stl).unwrap();
    fails(&loo(&d, &[&s(&q)]), 2, &["huge.stl"]);
}

#[test]
fn nan_and_infinite_coordinates() {
    let d = common::temp_dir("bad-nan");
    let p = d.join("nan.ply");
    std::fs::write(
        &p,
        TET_PLY_HEADER.to_string() + &TET_BODY.replace("0 1 0\n", "0 nan 0\n"),
    )
    .unwrap();
    fails(&loo(&d, &[&s(&p)]), 2, &["nan.ply"]);
    let q = d.join("inf.txt");
    std::fs::write(&q, "0 0\n1 0\ninf 1\n0 1\n").unwrap();
    fails(&loo(&d, &[&s(&q)]), 2, &["inf.txt"]);
}

#[test]
fn an_empty_file() {
    let d = common::temp_dir("bad-empty");
    for name in ["empty.ply", "empty.stl", "empty.csv", "empty.txt"] {
        let p = d.join(name);
        std::fs::write(&p, "").unwrap();
        fails(&loo(&d, &[&s(&p)]), 2, &[name]);
    }
}

#[test]
fn a_mesh_with_no_facets() {
    let d = common::temp_dir("bad-no-facets");
    let p = d.join("points.ply");
    std::fs::write(
        &p,
        TET_PLY_HEADER.replace("element face 4", "element face 0") + "0 0 0\n1 0 0\n0 1 0\n0 0 1\n",
    )
    .unwrap();
    fails(&loo(&d, &[&s(&p)]), 2, &["points.ply", "facet"]);
}

#[test]
fn zero_area_facets() {
    let d = common::temp_dir("bad-zero-area");
    // A tetrahedron with a sliver facet: vertex 5 is the midpoint of the edge 1-2.
    let p = d.join("sliver.obj");
    std::fs::write(
        &p,
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 0.5 0 0\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\nf 1 2 5\n",
    )
    .unwrap();
    fails(&loo(&d, &[&s(&p)]), 2, &["sliver.obj", "zero area"]);
}

#[test]
fn non_manifold_edges() {
    let d = common::temp_dir("bad-non-manifold");
    // Three triangles share the edge 0-1.
    let p = d.join("fin.obj");
    std::fs::write(
        &p,
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 2 5\n",
    )
    .unwrap();
    fails(&loo(&d, &[&s(&p)]), 2, &["fin.obj", "edge"]);
}

#[test]
fn a_surface_that_cannot_be_oriented() {
    let d = common::temp_dir("bad-moebius");
    // A Möbius strip of 8 quads (16 triangles).
    let n = 8;
    let mut text = String::new();
    for i in 0..n {
        let t = i as f64 / n as f64 * std::f64::consts::TAU;
        for w in [-0.3, 0.3] {
            let r = 1.0 + w * (t / 2.0).cos();
            text.push_str(&format!(
                "v {} {} {}\n",
                r * t.cos(),
                r * t.sin(),
                w * (t / 2.0).sin()
            ));
        }
    }
    for i in 0..n {
        let (a, b) = (2 * i + 1, 2 * i + 2);
        let (c, e) = if i + 1 < n {
            (2 * i + 3, 2 * i + 4)
        } else {
            (2, 1) // the half twist: the last quad joins the first with its sides swapped
        };
        text.push_str(&format!("f {a} {b} {e}\nf {a} {e} {c}\n"));
    }
    let p = d.join("moebius.obj");
    std::fs::write(&p, text).unwrap();
    fails(&loo(&d, &[&s(&p)]), 2, &["moebius.obj", "orient"]);
}

#[test]
fn an_open_surface_where_a_closed_one_is_needed() {
    let d = common::temp_dir("bad-open");
    // Each surface with its facets around one vertex removed: open, and no template mesh.
    let mut files = Vec::new();
    for (k, mut sh) in atlasmesh::study::demo_population_3d(5, 8, 3)
        .unwrap()
        .into_iter()
        .enumerate()
    {
        sh.facets.retain(|f| !f.contains(&0));
        let p = d.join(format!("open{k}.ply"));
        atlasmesh::formats::write_ply(&p, &sh).unwrap();
        files.push(s(&p));
    }
    let refs: Vec<&str> = files.iter().map(String::as_str).collect();
    fails(&loo(&d, &refs), 4, &["open", "--template-mesh"]);
}

#[test]
fn a_self_intersecting_outline() {
    let d = common::temp_dir("bad-bowtie");
    // Bow ties (a figure of eight): the mean is self-intersecting too, and cannot be meshed.
    let mut csv = String::from("shape,point,x,y\n");
    for k in 0..5 {
        let w = 1.0 + 0.05 * k as f64;
        for (i, (x, y)) in [(0.0, 0.0), (w, 1.0), (w, 0.0), (0.0, 1.0)]
            .iter()
            .enumerate()
        {
            csv.push_str(&format!("b{k},{i},{x},{y}\n"));
        }
    }
    let p = d.join("bowtie.csv");
    std::fs::write(&p, csv).unwrap();
    // Meshing the mean fails: the invalid-mesh class.
    fails(&loo(&d, &[&s(&p), "--closed"]), 4, &["intersects itself"]);
}

/// A CSV of `n` closed outlines of 40 points (ellipses varying in two ways).
fn outlines_csv(d: &Path, n: usize) -> PathBuf {
    let mut csv = String::from("shape,point,x,y\n");
    for k in 0..n {
        for i in 0..40 {
            let t = i as f64 / 40.0 * std::f64::consts::TAU;
            let a = 1.0 + 0.1 * (k as f64 * 1.3).sin();
            let b = 0.6 + 0.05 * (k as f64 * 0.7).cos();
            csv.push_str(&format!("s{k},{i},{},{}\n", a * t.cos(), b * t.sin()));
        }
    }
    let p = d.join("pop.csv");
    std::fs::write(&p, csv).unwrap();
    p
}

#[test]
fn a_landmark_index_out_of_range() {
    let d = common::temp_dir("bad-landmark-index");
    let pop = outlines_csv(&d, 5);
    let lm = d.join("lm.csv");
    let mut text = String::from("shape,landmark,index\n");
    for k in 0..5 {
        text.push_str(&format!(
            "s{k},0,3\ns{k},1,{}\n",
            if k == 2 { 400 } else { 20 }
        ));
    }
    std::fs::write(&lm, text).unwrap();
    fails(
        &loo(
            &d,
            &[&s(&pop), "--closed", "--register", "--landmarks", &s(&lm)],
        ),
        2,
        &["lm.csv", "400"],
    );
}

#[test]
fn landmark_counts_that_differ_between_shapes() {
    let d = common::temp_dir("bad-landmark-count");
    let pop = outlines_csv(&d, 5);
    let lm = d.join("lm.csv");
    let mut text = String::from("shape,landmark,index\n");
    for k in 0..5 {
        text.push_str(&format!("s{k},0,3\n"));
        if k != 3 {
            text.push_str(&format!("s{k},1,20\n"));
        }
    }
    std::fs::write(&lm, text).unwrap();
    // Landmarks are paired by id: landmark 1, which s3 lacks, is not used (a warning in the
    // report for each shape that has it); landmark 0 is.
    let out = d.join("out");
    let o = atlasmesh(&[
        "loo",
        "--shapes",
        &s(&pop),
        "--closed",
        "--register",
        "--landmarks",
        &s(&lm),
        "--no-plots",
        "--out",
        &s(&out),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r: atlasmesh::report::Report =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    for i in &r.inputs {
        let warned = i.warnings.iter().any(|w| w.contains("landmark(s) [1]"));
        assert_eq!(warned, i.name != "s3", "{}: {:?}", i.name, i.warnings);
    }
}

#[test]
fn two_d_and_three_d_shapes_mixed() {
    let d = common::temp_dir("bad-mixed");
    let pop = outlines_csv(&d, 3);
    let ply = binary_ply(&d);
    fails(
        &loo(&d, &[&s(&pop), &s(&ply)]),
        2,
        &["2D and 3D", "pop.csv"],
    );
}

#[test]
fn a_population_of_one_or_two_shapes() {
    let d = common::temp_dir("bad-too-few");
    for n in [1, 2] {
        let pop = outlines_csv(&d, n);
        fails(&loo(&d, &[&s(&pop), "--closed"]), 2, &["population"]);
    }
}

#[test]
fn identical_shapes() {
    let d = common::temp_dir("bad-identical");
    let mut csv = String::from("shape,point,x,y\n");
    for k in 0..5 {
        for i in 0..40 {
            let t = i as f64 / 40.0 * std::f64::consts::TAU;
            csv.push_str(&format!("s{k},{i},{},{}\n", t.cos(), 0.6 * t.sin()));
        }
    }
    let p = d.join("same.csv");
    std::fs::write(&p, csv).unwrap();
    fails(&loo(&d, &[&s(&p), "--closed"]), 2, &["variance"]);
}

/// An atlas of the demo's 2D outlines, built through the CLI.
pub(crate) fn atlas_2d(d: &Path) -> PathBuf {
    let pop = atlasmesh::study::demo_population(12, 120, 5);
    let mut csv = String::from("shape,point,x,y\n");
    for sh in &pop {
        for (i, p) in sh.points.iter().enumerate() {
            csv.push_str(&format!("{},{i},{},{}\n", sh.name, p[0], p[1]));
        }
    }
    let p = d.join("demo.csv");
    std::fs::write(&p, csv).unwrap();
    let atlas = d.join("demo.safetensors");
    let o = atlasmesh(&[
        "build",
        "--shapes",
        &s(&p),
        "--closed",
        "--modes",
        "4",
        "--element-size",
        "6%",
        "--no-plots",
        "--out",
        &s(&atlas),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    atlas
}

fn fit(d: &Path, atlas: &Path, subject: &Path) -> Output {
    atlasmesh(&[
        "fit",
        "--atlas",
        &s(atlas),
        "--subject",
        &s(subject),
        "--no-plots",
        "--out",
        &s(&d.join("fit")),
    ])
}

#[test]
fn a_subject_far_outside_the_model_is_refused() {
    let d = common::temp_dir("bad-far");
    let atlas = atlas_2d(&d);
    // A five-pointed star: nothing the bone-like model can make.
    let star: String = (0..200)
        .map(|i| {
            let t = i as f64 / 200.0 * std::f64::consts::TAU;
            let r = 1.0 + 0.8 * (5.0 * t).cos();
            format!("{} {}\n", r * t.cos(), r * t.sin())
        })
        .collect();
    let p = d.join("star.txt");
    std::fs::write(&p, star).unwrap();
    let o = fit(&d, &atlas, &p);
    // A batch: the subject failed (exit 6), its class is "did not converge" (5), no mesh.
    fails(&o, 6, &["star", "did not converge", "--max-misfit"]);
    let r: atlasmesh::report::Report =
        serde_json::from_slice(&std::fs::read(d.join("fit/report.json")).unwrap()).unwrap();
    assert_eq!(r.failed[0].exit_code, 5);
    assert!(
        files_in(&d.join("fit"))
            .iter()
            .all(|f| !f.to_string_lossy().contains("_mesh")),
        "no mesh for a subject that did not converge"
    );
}

#[test]
fn a_subject_in_another_unit_fits() {
    let d = common::temp_dir("bad-unit");
    let atlas = atlas_2d(&d);
    // A held-out demo shape in "micrometres": 1000 times larger.
    let shape = &atlasmesh::study::demo_population(13, 120, 5)[12];
    let text: String = shape
        .points
        .iter()
        .map(|p| format!("{} {}\n", 1000.0 * p[0], 1000.0 * p[1]))
        .collect();
    let p = d.join("big.txt");
    std::fs::write(&p, text).unwrap();
    let o = fit(&d, &atlas, &p);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r: atlasmesh::report::Report =
        serde_json::from_slice(&std::fs::read(d.join("fit/report.json")).unwrap()).unwrap();
    assert!(
        r.subjects[0].success,
        "{:?}",
        r.subjects[0].rms_distance_relative
    );
    assert_eq!(r.subjects[0].inverted_elements, 0);
}

#[test]
fn an_atlas_of_another_format_version() {
    let d = common::temp_dir("bad-atlas-version");
    let atlas = atlas_2d(&d);
    let mut b = std::fs::read(&atlas).unwrap();
    let at = b
        .windows(20)
        .position(|w| w == b"\"format_version\":\"3\"")
        .expect("version in the header");
    b[at + 18] = b'1';
    let old = d.join("old.safetensors");
    std::fs::write(&old, &b).unwrap();
    let subject = d.join("demo.csv");
    fails(
        &fit(&d, &old, &subject),
        2,
        &["old.safetensors", "format version", "rebuild"],
    );
}

#[test]
fn a_corrupted_atlas() {
    let d = common::temp_dir("bad-atlas-crc");
    let atlas = atlas_2d(&d);
    let mut b = std::fs::read(&atlas).unwrap();
    let n = b.len();
    b[n - 100] ^= 0x10; // a bit of the tensors flipped
    let bad = d.join("flipped.safetensors");
    std::fs::write(&bad, &b).unwrap();
    let subject = d.join("demo.csv");
    fails(
        &fit(&d, &bad, &subject),
        2,
        &["flipped.safetensors", "checksum"],
    );
    // Cut short.
    let cut = d.join("cut.safetensors");
    std::fs::write(&cut, &b[..n / 2]).unwrap();
    fails(&fit(&d, &cut, &subject), 2, &["cut.safetensors"]);
}

#[test]
fn an_atlas_of_the_wrong_dimension() {
    let d = common::temp_dir("bad-atlas-dim");
    let atlas = atlas_2d(&d);
    let ply = binary_ply(&d);
    let o = fit(&d, &atlas, &ply);
    fails(&o, 6, &["good.ply", "a 3D surface, but the atlas", "is 2D"]);
}

#[test]
fn an_unwritable_output_folder() {
    let d = common::temp_dir("bad-unwritable");
    let pop = outlines_csv(&d, 6);
    // A file where the output folder should be.
    let out = d.join("taken");
    std::fs::write(&out, "").unwrap();
    let o = atlasmesh(&[
        "loo",
        "--shapes",
        &s(&pop),
        "--closed",
        "--no-plots",
        "--out",
        &s(&out),
    ]);
    fails(&o, 3, &["taken", "not a folder"]);
}

#[test]
fn a_missing_input_file() {
    let d = common::temp_dir("bad-missing");
    let p = d.join("nowhere.ply");
    fails(&loo(&d, &[&s(&p)]), 3, &["nowhere.ply"]);
}

#[cfg(unix)]
#[test]
fn a_full_disk() {
    // The shell's file-size limit makes every write beyond 16 KiB fail as on a full disk
    // (SIGXFSZ ignored, so the write returns the error instead of killing the process).
    let d = common::temp_dir("bad-full-disk");
    let pop = outlines_csv(&d, 6);
    let out = d.join("out");
    let cmd = format!(
        "trap '' XFSZ; ulimit -f 16; exec '{}' loo --shapes '{}' --closed --no-plots --quiet --out '{}'",
        env!("CARGO_BIN_EXE_atlasmesh"),
        pop.display(),
        out.display()
    );
    let o = crate::common::run(
        Command::new("sh").arg("-c").arg(&cmd),
        crate::common::deadline::ATLASMESH,
    );
    // Every fold fails to write its mesh: each is listed with the I/O error, the report
    // (small) is written, exit 6.
    fails(&o, 6, &["File too large", "6 of 6 subjects failed"]);
    let r: atlasmesh::report::Report =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(r.failed.len(), 6);
    assert!(r.failed.iter().all(|f| f.exit_code == 3), "{:?}", r.failed);
    // Whatever was written is whole: no temporary file, and every mesh reads.
    for f in files_in(&out) {
        let name = f.file_name().unwrap().to_string_lossy().into_owned();
        assert!(!name.contains(".tmp-"), "temporary file left: {name}");
        if name.ends_with(".vtu") {
            atlasmesh::formats::read_vtu(&f).unwrap();
        }
    }
}

#[test]
fn a_bad_parameter() {
    let d = common::temp_dir("bad-parameter");
    let pop = outlines_csv(&d, 6);
    fails(
        &loo(&d, &[&s(&pop), "--closed", "--variance", "1.5"]),
        2,
        &["variance"],
    );
}

/// `voxel-mesh --join`: a mesh that is not there, a tolerance that is no distance, a set name
/// a solver file cannot hold: each refused before anything is written, the output folder not
/// made.
#[test]
fn voxel_mesh_join_refuses_what_it_cannot_tie() {
    let d = common::temp_dir("bad-join");
    let labels = d.join("seg.nii.gz");
    std::fs::write(&labels, b"not read: the arguments are checked first").unwrap();
    let bone = d.join("bone.inp");
    std::fs::write(&bone, b"*NODE\n").unwrap();
    let out = d.join("out");
    let run = |extra: &[&str]| {
        let mut args = vec![
            "voxel-mesh".to_string(),
            s(&labels),
            "--part".into(),
            "PADS=5,6".into(),
            "--out".into(),
            s(&out),
        ];
        args.extend(extra.iter().map(|a| a.to_string()));
        atlasmesh(&args)
    };
    let missing = s(&d.join("missing.inp"));
    fails(&run(&["--join", &missing]), 3, &["missing.inp"]);
    fails(
        &run(&["--join", &s(&bone), "--tie-tolerance", "NaN"]),
        2,
        &["--tie-tolerance NaN"],
    );
    fails(
        &run(&["--join", &s(&bone), "--tie-tolerance=-1"]),
        2,
        &["--tie-tolerance -1"],
    );
    fails(
        &run(&["--join", &s(&bone), "--join-name", "A B"]),
        2,
        &["--join-name A B", "not allowed"],
    );
    assert!(!out.exists());
    // --join-name and --tie-tolerance mean nothing without --join.
    let o = run(&["--tie-tolerance", "2"]);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(!out.exists());
}
