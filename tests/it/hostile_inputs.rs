//! Questionable and hostile input files through the command line with its default options:
//! set names that would break a format, coordinates that overflow, landmarks paired by id,
//! duplicated PLY properties, NaN in a sets file, lists of lists, broken links, huge surfaces
//! refused within 1 GiB of memory.

use crate::bad_input::{atlas_2d, fails, files_in};
use crate::common::{self, atlasmesh};
use crate::hostile_outputs::{ellipse, in_1gib, limited};
use std::path::{Path, PathBuf};

fn s(p: &Path) -> String {
    p.display().to_string()
}

fn fit(atlas: &Path, subject: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    let (a, sub, o) = (s(atlas), s(subject), s(out));
    let mut args = vec!["fit", "--atlas", &a, "--subject", &sub, "--out", &o];
    args.extend_from_slice(extra);
    atlasmesh(&args)
}

/// Set names from an atlas, an `.inp`, a `.msh` or a sets file that would break a format or
/// inject a line (`*INCLUDE, INPUT=/etc/passwd` after a newline) are refused by one rule,
/// with the name and the rule in the message; nothing is written.
#[test]
fn set_names_follow_one_rule_everywhere() {
    let d = common::temp_dir("hostile-set-names");
    let good = atlas_2d(&d);
    let subject = d.join("e.txt");
    std::fs::write(&subject, ellipse(1.0, 0.6)).unwrap();
    for (k, name) in [
        "X\n*INCLUDE, INPUT=/etc/passwd",
        "a\"/><evil",
        "Left Face",
        "",
    ]
    .into_iter()
    .enumerate()
    {
        let mut atlas = atlasmesh::model::Atlas::<2>::load(&good).unwrap();
        atlas.mesh.sets.node_sets.insert(name.into(), vec![0, 1]);
        let bad = d.join(format!("named{k}.safetensors"));
        atlas.save(&bad).unwrap();
        let out = d.join(format!("fit-named{k}"));
        let o = fit(&bad, &subject, &out, &["--format", "inp,vtu,msh,feb"]);
        fails(&o, 2, &[&format!("named{k}.safetensors"), "a set name is"]);
        assert!(files_in(&out).is_empty(), "{:?}", files_in(&out));
    }
    // A mesh file's names: Abaqus, Gmsh, VTK.
    let inp = d.join("m.inp");
    std::fs::write(
        &inp,
        "*NODE\n1, 0, 0\n2, 1, 0\n3, 1, 1\n4, 0, 1\n*ELEMENT, TYPE=CPS4\n1, 1, 2, 3, 4\n*NSET, NSET=A<B\n1, 2\n",
    )
    .unwrap();
    let msh = d.join("m.msh");
    std::fs::write(
        &msh,
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n2 1 \"a&b\"\n$EndPhysicalNames\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 1 1 0\n4 0 1 0\n$EndNodes\n$Elements\n1\n1 3 2 1 1 1 2 3 4\n$EndElements\n",
    )
    .unwrap();
    for (m, name) in [(&inp, "A<B"), (&msh, "a&b")] {
        let out = d.join("converted.vtu");
        let o = atlasmesh(&["convert", &s(m), &s(&out)]);
        fails(&o, 2, &[&s(m), name, "a set name is"]);
        assert!(!out.exists());
    }
    // The sets file.
    let sets = d.join("sets.toml");
    std::fs::write(
        &sets,
        "[[node_set]]\nname = \"A&B\"\nbox = { min = [0, 0], max = [1, 0.1] }\n",
    )
    .unwrap();
    let out = d.join("fit-sets");
    let o = fit(&good, &subject, &out, &["--sets", &s(&sets)]);
    fails(&o, 2, &["sets.toml", "A&B", "a set name is"]);
    // NaN bounds.
    std::fs::write(
        &sets,
        "[[node_set]]\nname = \"LOW\"\nbox = { min = [0, nan], max = [1, 0.1] }\n",
    )
    .unwrap();
    let o = fit(&good, &subject, &out, &["--sets", &s(&sets)]);
    fails(&o, 2, &["sets.toml", "LOW", "not a finite number"]);
    assert!(files_in(&out).is_empty(), "{:?}", files_in(&out));
}

/// Coordinates so large that areas and Jacobians overflow (1e200 in an outline, a mesh
/// scaled to 1e307) are refused with what to do, not reported as zero area, NaN % or a
/// perfect mesh.
#[test]
fn overflowing_coordinates_are_refused() {
    let d = common::temp_dir("hostile-overflow");
    let atlas = atlas_2d(&d);
    let big: String = ellipse(1.0, 0.6)
        .lines()
        .map(|l| {
            let v: Vec<f64> = l
                .split(' ')
                .map(|x| x.parse::<f64>().unwrap() * 1e200)
                .collect();
            format!("{:e} {:e}\n", v[0], v[1])
        })
        .collect();
    let subject = d.join("huge.txt");
    std::fs::write(&subject, big).unwrap();
    let out = d.join("fit");
    let o = fit(&atlas, &subject, &out, &[]);
    fails(&o, 6, &["huge.txt", "beyond", "rescale"]);
    let mesh = d.join("big.inp");
    std::fs::write(
        &mesh,
        "*NODE\n1, 0, 0\n2, 1e307, 0\n3, 1e307, 1e307\n4, 0, 1e307\n*ELEMENT, TYPE=CPS4\n1, 1, 2, 3, 4\n",
    )
    .unwrap();
    let o = atlasmesh(&["quality", &s(&mesh)]);
    fails(&o, 2, &["big.inp", "node 2", "rescale"]);
}

/// Landmarks are paired by id, not by their order in the files: a shape whose Scalismo file
/// lists the ids in another order gets the same landmarks; an id not in every shape is not
/// used (a warning); duplicated ids, no id in common and two landmarks on one point are
/// refused (duplicates once collapsed the template to a point, exit 0).
#[test]
fn landmarks_are_paired_by_id() {
    let d = common::temp_dir("hostile-landmarks");
    let ring = |k: usize| -> Vec<[f64; 2]> {
        (0..60)
            .map(|i| {
                let t = i as f64 / 60.0 * std::f64::consts::TAU;
                [(1.0 + 0.05 * k as f64) * t.cos(), 0.6 * t.sin()]
            })
            .collect()
    };
    let json = |pts: &[(&str, [f64; 2])]| {
        let items: Vec<String> = pts
            .iter()
            .map(|(id, p)| format!(r#"{{"id":"{id}","coordinates":[{},{}]}}"#, p[0], p[1]))
            .collect();
        format!("[{}]", items.join(","))
    };
    let mut shapes = Vec::new();
    let mut files: Vec<PathBuf> = Vec::new();
    for k in 0..5 {
        let pts = ring(k);
        let f = d.join(format!("s{k}.txt"));
        let text: String = pts.iter().map(|p| format!("{} {}\n", p[0], p[1])).collect();
        std::fs::write(&f, text).unwrap();
        shapes.push(f);
        let (a, b, c) = (pts[0], pts[15], pts[30]);
        // Shape 2 lists its landmarks in another order.
        let l = if k == 2 {
            json(&[("tip", c), ("front", a), ("side", b)])
        } else {
            json(&[("front", a), ("side", b), ("tip", c)])
        };
        let lf = d.join(format!("s{k}.json"));
        std::fs::write(&lf, l).unwrap();
        files.push(lf);
    }
    // The shapes as read, with the landmarks of `files`, and how they were paired.
    let paired = |files: &[PathBuf]| {
        let mut read: Vec<atlasmesh::geometry::Shape<2>> = shapes
            .iter()
            .map(|f| {
                atlasmesh::formats::read_outlines(f, true)
                    .unwrap()
                    .remove(0)
            })
            .collect();
        let pairing = atlasmesh::study::attach_landmarks(&mut read, files).unwrap();
        (read, pairing)
    };
    let (read, pairing) = paired(&files);
    assert_eq!(pairing.ids, ["front", "side", "tip"]);
    assert!(pairing.warnings.is_empty());
    for sh in &read {
        assert_eq!(sh.landmarks, read[0].landmarks, "{}", sh.name);
    }
    let run = |landmarks: &[PathBuf], out: &str| {
        let mut a: Vec<String> = vec!["loo".into(), "--shapes".into()];
        a.extend(shapes.iter().map(|p| s(p)));
        a.extend(["--closed".into(), "--landmarks".into()]);
        a.extend(landmarks.iter().map(|p| s(p)));
        a.extend(["--out".into(), s(&d.join(out))]);
        atlasmesh(&a)
    };
    // A duplicated id.
    let p = ring(3);
    std::fs::write(
        &files[3],
        json(&[("front", p[0]), ("front", p[15]), ("tip", p[30])]),
    )
    .unwrap();
    fails(
        &run(&files, "dup"),
        2,
        &["s3.json", "\"front\" is given twice"],
    );
    assert!(files_in(&d.join("dup")).is_empty());
    // An id that is not in every shape (a typo in one file, as in a real hand dataset): the
    // common ids are used, with a warning in the report naming the others.
    std::fs::write(
        &files[3],
        json(&[("front", p[0]), ("back", p[15]), ("tip", p[30])]),
    )
    .unwrap();
    let o = run(&files, "ids");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r: atlasmesh::report::Report =
        serde_json::from_slice(&std::fs::read(d.join("ids/report.json")).unwrap()).unwrap();
    let warned = |name: &str, id: &str| {
        r.inputs.iter().any(|i| {
            i.name == name
                && i.warnings.iter().any(|w| {
                    w.contains(&format!("landmark(s) [{id}]")) && w.contains("not in every shape")
                })
        })
    };
    assert!(
        warned("s3", "back") && warned("s0", "side"),
        "{:?}",
        r.inputs
    );
    let (read, pairing) = paired(&files);
    assert_eq!(pairing.ids, ["front", "tip"]);
    assert!(read.iter().all(|s| s.landmarks == [0, 30]));
    // No id in common.
    std::fs::write(&files[3], json(&[("a", p[0]), ("b", p[15]), ("c", p[30])])).unwrap();
    fails(
        &run(&files, "none"),
        2,
        &["no landmark id is in every shape", "paired by id"],
    );
    // Two landmarks on one point.
    std::fs::write(
        &files[3],
        json(&[("front", p[0]), ("side", p[0]), ("tip", p[30])]),
    )
    .unwrap();
    fails(
        &run(&files, "same"),
        2,
        &["s3.json", "fall on the same point"],
    );
}

/// A PLY declaring a property twice (which value is `x`?) or an element twice is refused.
#[test]
fn duplicated_ply_declarations_are_refused() {
    let d = common::temp_dir("hostile-ply");
    let atlas = d.join("none.safetensors");
    let tet = "0 0 0 0\n1 0 0 1\n0 1 0 2\n0 0 1 3\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
    let f = d.join("twice.ply");
    std::fs::write(
        &f,
        format!("ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nproperty float x\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n{tet}"),
    )
    .unwrap();
    // Read as a population: the error names the file and the property.
    let o = atlasmesh(&["build", "--shapes", &s(&f), &s(&f), "--out", &s(&atlas)]);
    fails(
        &o,
        2,
        &[
            "twice.ply",
            "property \"x\" of element vertex is declared twice",
        ],
    );
    assert!(!atlas.exists());
}

/// Lists inside a `.list` file are named as such (not read as outlines); a link that loops in
/// a subjects folder is a failed subject with its reason, not skipped without a word.
#[test]
fn lists_of_lists_and_looping_links_are_named() {
    let d = common::temp_dir("hostile-lists");
    let atlas = atlas_2d(&d);
    std::fs::write(d.join("e.txt"), ellipse(1.0, 0.6)).unwrap();
    std::fs::write(d.join("inner.list"), "e.txt\n").unwrap();
    let outer = d.join("outer.list");
    std::fs::write(&outer, "e.txt\ninner.list\n").unwrap();
    let out = d.join("fit-list");
    let o = fit(&atlas, &outer, &out, &[]);
    fails(&o, 2, &["outer.list", "inner.list", "a list inside a list"]);
    assert!(files_in(&out).is_empty());
    let folder = d.join("subjects");
    std::fs::create_dir_all(&folder).unwrap();
    std::fs::write(folder.join("good.txt"), ellipse(1.0, 0.6)).unwrap();
    std::os::unix::fs::symlink(folder.join("loop.txt"), folder.join("loop.txt")).unwrap();
    let out = d.join("fit-loop");
    let o = atlasmesh(&[
        "fit",
        "--atlas",
        &s(&atlas),
        "--subjects",
        &s(&folder),
        "--out",
        &s(&out),
    ]);
    fails(&o, 6, &["loop.txt", "1 of 2 subjects failed"]);
    let r: atlasmesh::report::Report =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(r.subjects.len(), 1);
    assert_eq!(r.failed[0].name, "loop");
}

/// Inputs refused for their size or kind take less than 1 GiB of memory (the commands run
/// under `ulimit -v 1 GiB`): a surface of 10 million vertices (beyond the point limit, from
/// its header), an OBJ of 4.5 million vertices with a lower limit (found while parsing), a
/// link to `/dev/zero`, a header announcing 4 billion faces.
#[test]
fn refused_inputs_stay_under_1_gib() {
    let d = common::temp_dir("hostile-memory");
    let atlas = atlas_2d(&d);
    // A binary PLY of 10 million vertices and one face (120 MB).
    let ply = d.join("huge.ply");
    {
        use std::io::Write;
        let n = 10_000_000usize;
        let mut w = std::io::BufWriter::new(std::fs::File::create(&ply).unwrap());
        write!(w, "ply\nformat binary_little_endian 1.0\nelement vertex {n}\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n").unwrap();
        for i in 0..n {
            for c in [i as f32, (i % 7) as f32, (i % 11) as f32] {
                w.write_all(&c.to_le_bytes()).unwrap();
            }
        }
        w.write_all(&[3]).unwrap();
        for i in [0i32, 1, 2] {
            w.write_all(&i.to_le_bytes()).unwrap();
        }
    }
    // (Read as a population: a 3D subject would be refused by the 2D atlas first.)
    let built = d.join("built.safetensors");
    let o = in_1gib(&["build", "--shapes", &s(&ply), &s(&ply), "--out", &s(&built)]);
    fails(
        &o,
        2,
        &["huge.ply", "10000000 points", "ATLASMESH_MAX_POINTS"],
    );
    std::fs::remove_file(&ply).unwrap();
    // An OBJ found too large while parsing.
    let obj = d.join("many.obj");
    {
        use std::io::Write;
        let mut w = std::io::BufWriter::new(std::fs::File::create(&obj).unwrap());
        for i in 0..4_500_000usize {
            writeln!(w, "v {i} {} {}", i % 7, i % 11).unwrap();
        }
        writeln!(w, "f 1 2 3").unwrap();
    }
    let o = limited(
        &format!("-v {}", crate::hostile_outputs::MEMORY_LIMIT_KIB),
        &["build", "--shapes", &s(&obj), &s(&obj), "--out", &s(&built)],
        &[("ATLASMESH_MAX_POINTS", "1000000")],
    );
    fails(
        &o,
        2,
        &["many.obj", "4500000 points", "limit of 1000000 points"],
    );
    std::fs::remove_file(&obj).unwrap();
    // A device and an absurd header.
    let zero = d.join("zero.txt");
    std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
    let out = d.join("fit-zero");
    let o = in_1gib(&[
        "fit",
        "--atlas",
        &s(&atlas),
        "--subject",
        &s(&zero),
        "--out",
        &s(&out),
    ]);
    fails(&o, 6, &["zero.txt", "not a regular file"]);
    let absurd = d.join("absurd.ply");
    std::fs::write(
        &absurd,
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 4000000000\nproperty list uchar int vertex_indices\nend_header\n",
    )
    .unwrap();
    let o = in_1gib(&[
        "build",
        "--shapes",
        &s(&absurd),
        &s(&absurd),
        "--out",
        &s(&built),
    ]);
    fails(&o, 2, &["absurd.ply", "implausibly large"]);
    assert!(!built.exists());
}

/// A broken legacy VTK file is named broken, with the line and what is missing, whatever it
/// was meant to hold (it used to be reported as "a 2D outline").
#[test]
fn a_broken_vtk_is_named_for_what_is_wrong() {
    let d = common::temp_dir("hostile-vtk");
    let atlas = atlas_2d(&d);
    let f = d.join("broken.vtk");
    std::fs::write(
        &f,
        "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0 0 0 1 0 0\n",
    )
    .unwrap();
    let out = d.join("fit");
    let o = fit(&atlas, &f, &out, &[]);
    fails(&o, 6, &["broken.vtk:6", "truncated", "POINTS"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("outline"), "{err}");
}
