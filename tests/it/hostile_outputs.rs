//! What a run writes when things go wrong, through the command line with its default options
//! (plots on): a batch in which no subject succeeds, a full disk or a file-size limit, a
//! repair that cannot untangle, two runs into one folder.

use crate::bad_input::{atlas_2d, fails, files_in};
use crate::common::{self, atlasmesh};
use std::path::Path;
use std::process::{Command, Output};

fn s(p: &Path) -> String {
    p.display().to_string()
}

/// The outline of an ellipse, as text.
pub(crate) fn ellipse(a: f64, b: f64) -> String {
    (0..120)
        .map(|i| {
            let t = i as f64 / 120.0 * std::f64::consts::TAU;
            format!("{} {}\n", a * t.cos(), b * t.sin())
        })
        .collect()
}

/// The largest address space a refused input may take: 1 GiB, in KiB for `ulimit -v`.
pub(crate) const MEMORY_LIMIT_KIB: u64 = 1 << 20;

/// `atlasmesh ARGS` under a shell limit (`ulimit LIMIT`, e.g. `-v 1048576` or `-f 40`), with
/// the extra environment `env`.
pub(crate) fn limited(limit: &str, args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut c = Command::new("sh");
    c.arg("-c")
        .arg(format!("ulimit {limit} && exec \"$@\""))
        .arg("sh")
        .arg(env!("CARGO_BIN_EXE_atlasmesh"))
        .args(args);
    for (k, v) in env {
        c.env(k, v);
    }
    crate::common::run(&mut c, crate::common::deadline::ATLASMESH)
}

/// Under 1 GiB of address space.
pub(crate) fn in_1gib(args: &[&str]) -> Output {
    limited(&format!("-v {MEMORY_LIMIT_KIB}"), args, &[])
}

fn report(out: &Path) -> atlasmesh::report::Report {
    serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap()
}

/// Temporary files (`.NAME.tmp-PID`) anywhere under `dir`.
fn temporaries(dir: &Path) -> Vec<String> {
    let mut v = Vec::new();
    for e in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        let p = e.path();
        if p.is_dir() {
            v.extend(temporaries(&p));
        } else if e.file_name().to_string_lossy().contains(".tmp-") {
            v.push(s(&p));
        }
    }
    v
}

/// A batch in which no subject succeeds (a missing file), and a shard with no subject (a
/// Slurm array with more tasks than subjects), with plots on and 1 GiB of memory: the report
/// and its pictures are written, the exit code says what happened, nothing grows without end
/// (the E_d plot of no history once drew ticks until 22 GB).
#[test]
fn batches_with_no_success_stay_small() {
    let d = common::temp_dir("hostile-no-success");
    let atlas = atlas_2d(&d);
    let out = d.join("missing");
    let o = in_1gib(&[
        "fit",
        "--atlas",
        &s(&atlas),
        "--subject",
        &s(&d.join("missing.txt")),
        "--out",
        &s(&out),
    ]);
    fails(&o, 6, &["missing.txt", "1 of 1 subjects failed"]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(!stdout.contains("NaN"), "no NaN figure printed: {stdout}");
    let r = report(&out);
    assert_eq!((r.subjects.len(), r.failed.len()), (0, 1));
    for f in ["report.html", "e_d.png", "modes.png"] {
        assert!(out.join(f).is_file(), "{f}");
    }
    // An empty shard: one subject, the second of two shards.
    let one = d.join("one.txt");
    std::fs::write(&one, ellipse(1.0, 0.6)).unwrap();
    let out = d.join("empty-shard");
    let o = in_1gib(&[
        "fit",
        "--atlas",
        &s(&atlas),
        "--subject",
        &s(&one),
        "--shard",
        "1/2",
        "--out",
        &s(&out),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("nothing to do"), "{stdout}");
    assert!(!stdout.contains("NaN"), "{stdout}");
    let r = report(&out);
    assert_eq!((r.subjects.len(), r.failed.len()), (0, 0));
    assert!(out.join("report.html").is_file());
}

/// A file-size limit (as a full disk) without the shell ignoring SIGXFSZ: `build` and `fit`
/// fail with the file named and the system's words (no debug dump), and leave no temporary;
/// a temporary that a killed run left is removed by the next run that writes the same file.
#[test]
fn a_file_size_limit_leaves_no_temporary() {
    let d = common::temp_dir("hostile-fsize");
    let atlas = atlas_2d(&d);
    let pop = d.join("demo.csv");
    let built = d.join("built");
    let o = limited(
        "-f 4",
        &[
            "build",
            "--shapes",
            &s(&pop),
            "--closed",
            "--modes",
            "4",
            "--element-size",
            "6%",
            "--out",
            &s(&built.join("a.safetensors")),
        ],
        &[],
    );
    fails(&o, 3, &["a.safetensors", "File too large"]);
    assert!(temporaries(&built).is_empty(), "{:?}", temporaries(&built));
    let subject = d.join("e.txt");
    std::fs::write(&subject, ellipse(1.0, 0.6)).unwrap();
    let out = d.join("fit");
    let args = [
        "fit",
        "--atlas",
        &s(&atlas),
        "--subject",
        &s(&subject),
        "--out",
        &s(&out),
    ];
    let o = limited("-f 40", &args, &[]);
    fails(&o, 3, &["File too large"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("Kind(") && !err.contains("Os {"), "{err}");
    assert!(temporaries(&out).is_empty(), "{:?}", temporaries(&out));
    // What a run killed mid-write leaves (a process that no longer runs), then a full run.
    let stale = out.join(".e_d.png.tmp-4194302");
    std::fs::write(&stale, "half").unwrap();
    let o = atlasmesh(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(!stale.exists(), "the stale temporary is removed");
    assert!(temporaries(&out).is_empty(), "{:?}", temporaries(&out));
}

/// `repair` of a mesh it cannot untangle (an inverted quadrilateral whose nodes are all on
/// the boundary, which stays put without a surface) exits 4 and writes nothing.
#[test]
fn a_repair_that_fails_writes_nothing() {
    let d = common::temp_dir("hostile-repair");
    let mesh = d.join("inverted.inp");
    std::fs::write(
        &mesh,
        "*NODE\n1, 0, 0\n2, 0, 1\n3, 1, 1\n4, 1, 0\n*ELEMENT, TYPE=CPS4, ELSET=ALL\n1, 1, 2, 3, 4\n",
    )
    .unwrap();
    let out = d.join("repaired.vtu");
    let o = atlasmesh(&["repair", &s(&mesh), "--out", &s(&out)]);
    fails(
        &o,
        4,
        &["repaired.vtu", "still inverted", "no mesh written"],
    );
    assert!(!out.exists());
    assert!(files_in(&d).len() == 1, "{:?}", files_in(&d));
}

/// Two runs into one `--out`: one holding the folder (here the test itself) makes the other
/// stop with a clear error before writing; a shard run into the folder of another shard's
/// finished report is refused instead of replacing it.
#[test]
fn two_runs_into_one_folder_are_refused() {
    let d = common::temp_dir("hostile-lock");
    let atlas = atlas_2d(&d);
    let subjects = d.join("subjects");
    std::fs::create_dir_all(&subjects).unwrap();
    for k in 0..2 {
        std::fs::write(
            subjects.join(format!("e{k}.txt")),
            ellipse(1.0 + 0.05 * k as f64, 0.6),
        )
        .unwrap();
    }
    let out = d.join("out");
    std::fs::create_dir_all(&out).unwrap();
    let args = |shard: &str| {
        vec![
            "fit".to_string(),
            "--atlas".into(),
            s(&atlas),
            "--subjects".into(),
            s(&subjects),
            "--shard".into(),
            shard.into(),
            "--out".into(),
            s(&out),
        ]
    };
    {
        let held = std::fs::File::open(&out).unwrap();
        held.try_lock().unwrap();
        let o = atlasmesh(&args("0/2"));
        fails(&o, 3, &["another atlasmesh run", "its own --out"]);
        assert!(files_in(&out).is_empty(), "{:?}", files_in(&out));
        let o = atlasmesh(&[
            "loo",
            "--shapes",
            &s(&d.join("demo.csv")),
            "--closed",
            "--out",
            &s(&out),
        ]);
        fails(&o, 3, &["another atlasmesh run"]);
    }
    let o = atlasmesh(&args("0/2"));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let before = std::fs::read(out.join("report.json")).unwrap();
    let o = atlasmesh(&args("1/2"));
    fails(
        &o,
        2,
        &["report.json", "shard 0/2", "shard 1/2", "merge-reports"],
    );
    assert_eq!(std::fs::read(out.join("report.json")).unwrap(), before);
    // The same shard again resumes.
    let o = atlasmesh(&args("0/2"));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// A subject with one vertex moved far away (a segmentation spike): whatever the fit makes of
/// it, no mesh with an inverted element is written as a success; every mesh written passes
/// `quality`, and a subject whose mesh could not be made valid is failed without a mesh.
#[test]
fn a_spike_never_gives_an_invalid_mesh() {
    let d = common::temp_dir("hostile-spike");
    let atlas = atlas_2d(&d);
    let subjects = d.join("subjects");
    std::fs::create_dir_all(&subjects).unwrap();
    for (k, far) in [2.0, 5.0, 50.0].into_iter().enumerate() {
        let mut lines: Vec<String> = ellipse(1.0, 0.6).lines().map(str::to_string).collect();
        lines[30] = format!("0 {far}");
        std::fs::write(subjects.join(format!("spike{k}.txt")), lines.join("\n")).unwrap();
    }
    let out = d.join("fit");
    let o = atlasmesh(&[
        "fit",
        "--atlas",
        &s(&atlas),
        "--subjects",
        &s(&subjects),
        "--format",
        "inp,vtu",
        "--out",
        &s(&out),
    ]);
    assert!(
        matches!(o.status.code(), Some(0 | 6)),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let r = report(&out);
    assert_eq!(r.subjects.len() + r.failed.len(), 3);
    for f in files_in(&out) {
        let name = f.file_name().unwrap().to_string_lossy().into_owned();
        if name.ends_with("_mesh.inp") || name.ends_with("_mesh.vtu") {
            let q = atlasmesh(&["quality", &s(&f)]);
            assert!(
                q.status.success(),
                "{name}: {}",
                String::from_utf8_lossy(&q.stdout)
            );
        }
    }
    for f in &r.failed {
        assert!(
            !out.join(&f.name)
                .join(format!("{}_mesh.vtu", f.name))
                .exists()
        );
        // A refused subject leaves no empty folder.
        let dir = out.join(&f.name);
        assert!(
            !dir.exists() || !files_in(&dir).is_empty(),
            "{}",
            dir.display()
        );
    }
}

#[test]
fn names_are_shown_safely_and_never_echoed_whole() {
    let d = common::temp_dir("hostile-names");
    let atlas = atlas_2d(&d);
    let subjects = d.join("subjects");
    std::fs::create_dir_all(&subjects).unwrap();
    // A right-to-left override in a file name (it would show as "okgnp.txt" reversed).
    std::fs::write(subjects.join("ok\u{202E}gnp.txt"), ellipse(1.0, 0.6)).unwrap();
    // A CSV whose shape name is 100 000 characters long.
    let long = "n".repeat(100_000);
    let mut csv = String::from("shape,point,x,y\n");
    for (k, l) in ellipse(1.0, 0.6).lines().enumerate() {
        let (x, y) = l.split_once(' ').unwrap();
        csv.push_str(&format!("{long},{k},{x},{y}\n"));
    }
    std::fs::write(subjects.join("long.csv"), csv).unwrap();
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
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(6), "{err}");
    assert!(
        err.len() < 2_000 && err.contains("100000 characters"),
        "{err}"
    );
    let r = report(&out);
    assert_eq!((r.subjects.len(), r.failed.len()), (1, 1), "{err}");
    assert!(r.failed[0].error.len() < 1_000);
    assert_eq!(r.subjects[0].name, "ok\u{FFFD}gnp");
    for f in files_in(&out) {
        // (report.json keeps the input's path as it is: it names the file.)
        if f.extension().is_some_and(|e| e == "html") {
            let text = std::fs::read_to_string(&f).unwrap();
            assert!(!text.contains('\u{202E}'), "{}", f.display());
        }
    }
}
