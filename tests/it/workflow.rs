//! The Snakemake workflow (`workflow/Snakefile`) run by Snakemake itself, locally: the atlas
//! built, the subjects fitted in shards, the shards' reports joined.

use crate::common;
use std::path::Path;
use std::process::Command;

/// Snakemake beside `ATLASMESH_PYTHON` (CI installs it there), or `None` (skipped, or a
/// failure with `ATLASMESH_REQUIRE_TOOLS`).
fn snakemake() -> Option<std::path::PathBuf> {
    let python = common::python()?;
    let program = python.with_file_name("snakemake");
    common::tool(&program.display().to_string(), "Snakemake workflow").then_some(program)
}

/// Runs the workflow with `config` in `dir` (its `.snakemake` folder and cache there).
fn run_workflow(snakemake: &Path, dir: &Path, config: &Path) -> std::process::Output {
    let snakefile = Path::new(env!("CARGO_MANIFEST_DIR")).join("workflow/Snakefile");
    common::run(
        Command::new(snakemake)
            .current_dir(dir)
            .env("XDG_CACHE_HOME", dir.join("cache"))
            .args(["--snakefile", &snakefile.display().to_string()])
            .args(["--configfile", &config.display().to_string()])
            .args(["--cores", "2"]),
        common::deadline::PYTHON,
    )
}

/// The workflow on the shared femurs: S002-S010 registered to S001 in two jobs, their atlas
/// (5 modes, 2 % elements), five subjects (a `.list` file) in two shards. The merged report holds the five, each with the
/// same figures as one `atlasmesh fit` of them all with the same atlas (times aside), each in
/// its shard's folder (subject k of the sorted list in shard k mod 2), `scores.csv` beside it;
/// run again, the workflow has nothing to do; a bad configuration is refused with its reason.
#[test]
fn the_snakemake_workflow_builds_fits_in_shards_and_merges() {
    let Some(data) = common::data_dir("the_snakemake_workflow_builds_fits_in_shards_and_merges")
    else {
        return;
    };
    let Some(snakemake) = snakemake() else {
        return;
    };
    let femurs = data.join("knee-distal-femur-synthetic-3d/femur");
    let femur = |k: usize| {
        femurs
            .join(format!("S{k:03}_Femur.ply"))
            .display()
            .to_string()
    };
    let dir = common::temp_dir("workflow");
    let subjects: Vec<String> = (11..=15).map(femur).collect();
    std::fs::write(dir.join("subjects.list"), subjects.join("\n")).unwrap();
    let shapes: Vec<String> = (2..=10).map(|k| format!("\"{}\"", femur(k))).collect();
    let config = dir.join("config.yaml");
    std::fs::write(
        &config,
        format!(
            "atlasmesh: \"{}\"\nshapes: [{}]\ntemplate: \"{}\"\nregister_shards: 2\n\
             subjects: subjects.list\nout: results\nshards: 2\n\
             build_options: \"--element-size 2% --modes 5\"\nfit_options: [\"--no-plots\"]\n",
            env!("CARGO_BIN_EXE_atlasmesh"),
            shapes.join(", "),
            femur(1)
        ),
    )
    .unwrap();
    let o = run_workflow(&snakemake, &dir, &config);
    let log = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{log}");
    let results = dir.join("results");
    // The registration in two jobs: the nine shapes in correspondence with the template.
    let mut registered = 0;
    for i in 0..2 {
        let list = results.join(format!("registration/shard-{i}/registered.list"));
        registered += std::fs::read_to_string(&list).unwrap().lines().count();
    }
    assert_eq!(registered, 9);
    let atlas = atlasmesh::model::Atlas::<3>::load(&results.join("atlas.safetensors")).unwrap();
    let template = atlasmesh::formats::read_surface(Path::new(&femur(1))).unwrap();
    assert_eq!(atlas.mean.len(), template.points.len());
    let merged: atlasmesh::report::Report =
        serde_json::from_slice(&std::fs::read(results.join("report.json")).unwrap()).unwrap();
    assert_eq!(merged.subjects.len(), 5, "{:?}", merged.failed);
    assert!(merged.failed.is_empty());
    let scores = std::fs::read_to_string(results.join("scores.csv")).unwrap();
    assert_eq!(scores.lines().count(), 6, "{scores}");
    for (k, s) in subjects.iter().enumerate() {
        let name = Path::new(s)
            .file_stem()
            .unwrap()
            .to_string_lossy()
            .to_string();
        let folder = results.join(format!("shard-{}/{name}", k % 2));
        assert!(
            folder.join("subject.json").is_file(),
            "{}",
            folder.display()
        );
    }
    // The same figures as one fit of the five with the same atlas.
    let alone = dir.join("alone");
    let o = common::atlasmesh(&[
        "fit",
        "--atlas",
        &results.join("atlas.safetensors").display().to_string(),
        "--subjects",
        &dir.join("subjects.list").display().to_string(),
        "--no-plots",
        "--out",
        &alone.display().to_string(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let one: atlasmesh::report::Report =
        serde_json::from_slice(&std::fs::read(alone.join("report.json")).unwrap()).unwrap();
    let mut by_name: Vec<_> = merged.subjects.iter().collect();
    by_name.sort_by(|a, b| a.name.cmp(&b.name));
    for (a, b) in by_name.iter().zip(&one.subjects) {
        assert_eq!(a.name, b.name);
        assert_eq!(a.sd, b.sd, "{}", a.name);
        assert_eq!(
            (
                a.mesh_rms_distance.to_bits(),
                a.scaled_jacobian_min.to_bits()
            ),
            (
                b.mesh_rms_distance.to_bits(),
                b.scaled_jacobian_min.to_bits()
            ),
            "{}",
            a.name
        );
        assert_eq!(a.success, b.success);
    }
    // Run again: every output is there and newer than its inputs.
    let o = run_workflow(&snakemake, &dir, &config);
    let log = String::from_utf8_lossy(&o.stderr);
    assert!(
        o.status.success() && log.contains("Nothing to be done"),
        "{log}"
    );
    // A configuration without its subjects, or with no shard: refused, saying which.
    for (bad, why) in [
        ("out: other\nshapes: a.ply\n", "has no `subjects`"),
        (
            "out: other\nshapes: a.ply\nsubjects: b.ply\nshards: 0\n",
            "shards = 0",
        ),
    ] {
        let config = dir.join("bad.yaml");
        std::fs::write(&config, bad).unwrap();
        let o = run_workflow(&snakemake, &dir, &config);
        let log = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && log.contains(why), "{bad}: {log}");
        assert!(!dir.join("other").exists());
    }
}
