//! Hostile and broken input through the command line with its default options (plots on):
//! names that would write outside `--out` or share a folder, meshes no solver could use.

use crate::bad_input::{atlas_2d, fails, files_in};
use crate::common::{self, atlasmesh};
use crate::hostile_outputs::ellipse;
use std::path::Path;

fn s(p: &Path) -> String {
    p.display().to_string()
}

/// Subjects named `..`, `.` (files `...txt`, `..txt`) write into folders of their own inside
/// `--out`, and touch nothing beside it; two files whose names make one folder (`S 1`,
/// `S_1`) are refused before anything is written.
#[test]
fn subject_names_stay_inside_out_and_apart() {
    let d = common::temp_dir("hostile-names");
    let atlas = atlas_2d(&d);
    let subjects = d.join("subjects");
    std::fs::create_dir_all(&subjects).unwrap();
    for f in ["...txt", "..txt", "plain.txt"] {
        std::fs::write(subjects.join(f), ellipse(1.0, 0.6)).unwrap();
    }
    // What a run must not touch: a file of the same name beside --out.
    std::fs::write(d.join("subject.json"), "keep").unwrap();
    let out = d.join("fit");
    let o = atlasmesh(&[
        "fit",
        "--atlas",
        &s(&atlas),
        "--subjects",
        &s(&subjects),
        "--out",
        &s(&out),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        std::fs::read_to_string(d.join("subject.json")).unwrap(),
        "keep"
    );
    let r: atlasmesh::report::Report =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(r.subjects.len(), 3);
    for sub in &r.subjects {
        for f in &sub.files {
            let p = out.join(f);
            assert!(p.is_file(), "{f} written");
            let canon = p.canonicalize().unwrap();
            assert!(
                canon.starts_with(out.canonicalize().unwrap()),
                "{f} inside --out"
            );
            assert!(
                !f.starts_with('.') && !f.contains("/."),
                "{f}: no hidden or relative name"
            );
        }
    }
    // Two names, one folder.
    let clash = d.join("clash");
    std::fs::create_dir_all(&clash).unwrap();
    for f in ["S 1.txt", "S_1.txt"] {
        std::fs::write(clash.join(f), ellipse(1.0, 0.6)).unwrap();
    }
    let out2 = d.join("fit2");
    let o = atlasmesh(&[
        "fit",
        "--atlas",
        &s(&atlas),
        "--subjects",
        &s(&clash),
        "--out",
        &s(&out2),
    ]);
    fails(&o, 2, &["S 1.txt", "S_1.txt", "S_1/", "rename one"]);
    assert!(files_in(&out2).is_empty(), "{:?}", files_in(&out2));
}

/// Atlas files with a valid checksum but contents no model has (written through the
/// library, so the checksum is right) are refused when read: exit 2, the file and the problem
/// named, nothing written. Among them an atlas whose mesh nodes overflow when morphed
/// (×1e300), which used to give all-NaN meshes counted as successes.
#[test]
fn inconsistent_atlases_are_refused_when_read() {
    let d = common::temp_dir("hostile-atlas");
    let good = atlas_2d(&d);
    let subject = d.join("ellipse.txt");
    std::fs::write(&subject, ellipse(1.0, 0.6)).unwrap();
    type Edit = fn(&mut atlasmesh::model::Atlas<2>);
    let cases: [(&str, Edit, &str); 10] = [
        (
            "overflow",
            |a| a.mesh.nodes.iter_mut().flatten().for_each(|c| *c *= 1e300),
            "degenerate",
        ),
        (
            "negative-eigenvalue",
            |a| a.eigenvalues[0] = -1.0,
            "eigenvalue",
        ),
        ("nan-eigenvalue", |a| a.eigenvalues[1] = f64::NAN, "NaN"),
        (
            "no-variance",
            |a| a.cumulative_variance.clear(),
            "cumulative variance",
        ),
        (
            "no-elements",
            |a| a.mesh.connectivity.clear(),
            "no elements",
        ),
        (
            "rising-eigenvalues",
            |a| a.eigenvalues.reverse(),
            "must not rise",
        ),
        ("no-mean", |a| a.mean.clear(), "out of range"),
        ("no-facets", |a| a.facets.clear(), "facets"),
        (
            "all-inverted",
            |a| a.mesh.connectivity.chunks_mut(4).for_each(|e| e.reverse()),
            "inverted",
        ),
        // The quadrilaterals' nodes read as triangles (another kind of this dimension).
        (
            "tri-kind",
            |a| a.mesh.kind = atlasmesh::mesh::ElementKind::Tri3,
            "degenerate",
        ),
    ];
    for (name, edit, word) in cases {
        let mut atlas = atlasmesh::model::Atlas::<2>::load(&good).unwrap();
        edit(&mut atlas);
        let bad = d.join(format!("{name}.safetensors"));
        atlas.save(&bad).unwrap();
        let out = d.join(format!("fit-{name}"));
        let o = atlasmesh(&[
            "fit",
            "--atlas",
            &s(&bad),
            "--subject",
            &s(&subject),
            "--out",
            &s(&out),
        ]);
        fails(&o, 2, &[&format!("{name}.safetensors"), word]);
        assert!(files_in(&out).is_empty(), "{name}: {:?}", files_in(&out));
    }
}

/// Inputs that are not regular files (a link to `/dev/zero`, a FIFO) are refused before they
/// are read (no endless read, no hang), and a file beyond the input limit is refused with the
/// limit and how to raise it.
#[test]
fn devices_fifos_and_oversized_inputs_are_refused() {
    let d = common::temp_dir("hostile-files");
    let atlas = atlas_2d(&d);
    let zero = d.join("zero.txt");
    std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
    let fifo = d.join("fifo.txt");
    let made = common::run(
        std::process::Command::new("mkfifo").arg(&fifo),
        common::deadline::SHORT,
    );
    assert!(made.status.success());
    for (p, name) in [(&zero, "zero"), (&fifo, "fifo")] {
        let out = d.join(format!("fit-{name}"));
        let o = atlasmesh(&[
            "fit",
            "--atlas",
            &s(&atlas),
            "--subject",
            &s(p),
            "--out",
            &s(&out),
        ]);
        fails(&o, 6, &[&format!("{name}.txt"), "not a regular file"]);
        assert!(
            files_in(&out)
                .iter()
                .all(|f| !f.to_string_lossy().contains("_mesh"))
        );
    }
    let big = d.join("big.txt");
    std::fs::write(&big, ellipse(1.0, 0.6).repeat(30)).unwrap();
    let out = d.join("fit-big");
    let o = crate::common::run(
        std::process::Command::new(env!("CARGO_BIN_EXE_atlasmesh"))
            .args([
                "fit",
                "--atlas",
                &s(&atlas),
                "--subject",
                &s(&big),
                "--out",
                &s(&out),
            ])
            .env("ATLASMESH_MAX_INPUT_BYTES", "60000"),
        crate::common::deadline::ATLASMESH,
    );
    fails(
        &o,
        6,
        &[
            "big.txt",
            "input limit of 60000 bytes",
            "ATLASMESH_MAX_INPUT_BYTES",
        ],
    );
    // A folder given as an atlas.
    let o = atlasmesh(&[
        "fit",
        "--atlas",
        &s(&d),
        "--subject",
        &s(&big),
        "--out",
        &s(&out),
    ]);
    fails(&o, 2, &["not a regular file"]);
}

/// Parameters out of their ranges are refused before any work, naming the option and the
/// range: `--grid 60` (9 GB), `--grid 1000`, `--resample 1e8`, `--repair-bound 2` and `NaN`,
/// `--jobs 100000`, `--alpha 0`.
#[test]
fn parameters_out_of_range_are_refused() {
    let d = common::temp_dir("hostile-params");
    let shapes = d.join("s.txt");
    std::fs::write(&shapes, ellipse(1.0, 0.6)).unwrap();
    let out = d.join("out");
    for (flag, value, words) in [
        ("--grid", "60", "from 4 to 32"),
        ("--grid", "1000", "from 4 to 32"),
        ("--resample", "100000000", "from 3 to 1000000"),
        ("--repair-bound", "2", "between 0 and 1"),
        ("--repair-bound", "NaN", "between 0 and 1"),
        ("--jobs", "100000", "from 0 to 1024"),
        ("--alpha", "0", "finite positive"),
        ("--starts", "0", "from 1 to 64"),
    ] {
        let o = atlasmesh(&[
            "loo",
            "--shapes",
            &s(&shapes),
            flag,
            value,
            "--out",
            &s(&out),
        ]);
        fails(&o, 2, &[flag, words]);
        assert!(files_in(&out).is_empty(), "{flag} {value}");
    }
}
