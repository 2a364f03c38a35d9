//! Batch fitting (issue 7) through the CLI on a seeded synthetic population of closed
//! surfaces (the 3D demo's; no data needed): resume after a kill gives the outputs of an
//! uninterrupted run, shards are disjoint and cover the list and their reports merge, and a
//! subject that fails is reported while the batch goes on.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::atlasmesh;

fn s(p: &Path) -> String {
    p.display().to_string()
}

/// An atlas of 16 synthetic surfaces and `n` other ones as subjects (PLY files).
fn setup(name: &str, n: usize) -> (common::TempDir, PathBuf, Vec<PathBuf>) {
    let d = common::temp_dir(name);
    let shapes = atlasmesh::study::demo_population_3d(16 + n, 12, 7).unwrap();
    let mut files = Vec::new();
    for (k, shape) in shapes.iter().enumerate() {
        let p = d.join(format!("shape{k:02}.ply"));
        atlasmesh::formats::write_ply(&p, shape).unwrap();
        files.push(p);
    }
    let atlas = d.join("atlas.safetensors");
    let mut args: Vec<String> = vec!["build".into(), "--shapes".into()];
    args.extend(files[..16].iter().map(|p| s(p)));
    args.extend(
        [
            "--modes",
            "4",
            "--element-size",
            "10%",
            "--no-plots",
            "--out",
        ]
        .map(String::from),
    );
    args.push(s(&atlas));
    let o = atlasmesh(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let subjects = d.join("subjects");
    std::fs::create_dir_all(&subjects).unwrap();
    let mut list = Vec::new();
    for f in &files[16..] {
        let to = subjects.join(f.file_name().unwrap());
        std::fs::rename(f, &to).unwrap();
        list.push(to);
    }
    (d, atlas, list)
}

fn fit_args(atlas: &Path, subjects: &Path, out: &Path) -> Vec<String> {
    vec![
        "fit".into(),
        "--atlas".into(),
        s(atlas),
        "--subjects".into(),
        s(subjects),
        "--no-plots".into(),
        "--out".into(),
        s(out),
    ]
}

fn report(out: &Path) -> atlasmesh::report::Report {
    serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap()
}

/// Every file of a batch folder (relative path, bytes), without report.json.
fn outputs(out: &Path) -> Vec<(String, Vec<u8>)> {
    let mut v = Vec::new();
    for e in std::fs::read_dir(out).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            for f in std::fs::read_dir(&p).unwrap() {
                let f = f.unwrap().path();
                let rel = f.strip_prefix(out).unwrap().display().to_string();
                v.push((rel, std::fs::read(&f).unwrap()));
            }
        }
    }
    v.sort();
    v
}

#[test]
fn a_killed_batch_resumes_where_it_stopped() {
    let (d, atlas, subjects) = setup("batch-resume", 24);
    let dir = subjects[0].parent().unwrap();
    // The whole batch at once.
    let whole = d.join("whole");
    let o = atlasmesh(&fit_args(&atlas, dir, &whole));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r = report(&whole);
    assert_eq!(r.summary.subjects, 24);
    assert_eq!(r.summary.meshes_valid, 24);
    assert_eq!(r.summary.resumed, 0);
    // Killed after a few subjects (one worker), then run again.
    let part = d.join("part");
    let mut args = fit_args(&atlas, dir, &part);
    args.extend(["--jobs".into(), "1".into()]);
    let mut child = Command::new(env!("CARGO_BIN_EXE_atlasmesh"))
        .args(&args)
        .arg("--quiet")
        .spawn()
        .unwrap();
    let records = |out: &Path| {
        std::fs::read_dir(out)
            .map(|r| {
                r.filter(|e| {
                    e.as_ref()
                        .is_ok_and(|e| e.path().join(atlasmesh::study::batch::RECORD).is_file())
                })
                .count()
            })
            .unwrap_or(0)
    };
    let t = std::time::Instant::now();
    while records(&part) < 4 && t.elapsed().as_secs() < 120 {
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    child.kill().unwrap();
    let status = child.wait().unwrap();
    assert!(!status.success(), "the batch was killed before its end");
    assert!(!part.join("report.json").exists());
    let done = records(&part);
    assert!((4..24).contains(&done), "{done} subjects done at the kill");
    // Whatever the kill left, no file under its final name is half-written: every mesh
    // there reads.
    for (f, _) in outputs(&part) {
        if f.ends_with("_mesh.vtu") {
            atlasmesh::formats::read_vtu(&part.join(&f)).unwrap();
        }
    }
    let o = atlasmesh(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r2 = report(&part);
    assert_eq!(r2.summary.resumed, done, "only the rest was fitted");
    assert_eq!(r2.summary.subjects, 24);
    // What each subject cost: its time (its fit's and more) and, made one at a time, the
    // heap's peak meanwhile; the run's resident peak. With several workers, no heap per subject.
    for s in &r2.subjects {
        assert!(
            s.seconds >= s.fit_seconds && s.seconds < 600.0,
            "{}: {} s, fit {} s",
            s.name,
            s.seconds,
            s.fit_seconds
        );
        let heap = s.heap_peak_mb.expect("one worker: the heap's peak");
        assert!(heap > 0.1 && heap < 24_000.0, "{}: {heap} MB", s.name);
    }
    let total: f64 = r2.subjects.iter().map(|s| s.seconds).sum();
    assert!((r2.summary.subject_seconds - total).abs() < 1e-9);
    assert!(r2.summary.heap_peak_mb.is_some());
    let rss = r2.resident_peak_mb.expect("the process's resident peak");
    assert!(rss > 1.0 && rss < 24_000.0, "{rss} MB");
    let several = std::thread::available_parallelism().map_or(1, |n| n.get()) > 1;
    assert_eq!(r.subjects.iter().all(|s| s.heap_peak_mb.is_none()), several);
    // The same outputs as the uninterrupted run, byte for byte (temporary files aside).
    let clean = |v: Vec<(String, Vec<u8>)>| -> Vec<(String, Vec<u8>)> {
        v.into_iter()
            .filter(|(f, _)| !f.contains(".tmp-"))
            .collect()
    };
    let (a, b) = (clean(outputs(&whole)), clean(outputs(&part)));
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(x.0, y.0);
        if x.0.ends_with(atlasmesh::study::batch::RECORD) {
            // The record holds the fit time.
            let strip = |v: &[u8]| {
                let mut r: atlasmesh::study::batch::SubjectRecord =
                    serde_json::from_slice(v).unwrap();
                r.report.fit_seconds = 0.0;
                r.report.seconds = 0.0;
                r.report.heap_peak_mb = None;
                r.input.clear();
                serde_json::to_string(&r).unwrap()
            };
            assert_eq!(strip(&x.1), strip(&y.1), "{}", x.0);
        } else {
            assert!(x.1 == y.1, "{} differs from the uninterrupted run", x.0);
        }
    }
    // A third run does nothing; a changed input is fitted again.
    let o = atlasmesh(&args);
    assert!(o.status.success());
    assert_eq!(report(&part).summary.resumed, 24);
    let shape = atlasmesh::formats::read_surface(&subjects[3]).unwrap();
    let mut moved = shape.clone();
    moved.points.iter_mut().for_each(|p| p[0] += 0.01);
    atlasmesh::formats::write_ply(&subjects[3], &moved).unwrap();
    let o = atlasmesh(&args);
    assert!(o.status.success());
    assert_eq!(report(&part).summary.resumed, 23);
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn shards_cover_the_batch_and_merge() {
    let (d, atlas, subjects) = setup("batch-shards", 7);
    let list = d.join("subjects.list");
    std::fs::write(
        &list,
        subjects
            .iter()
            .map(|p| format!("subjects/{}\n", p.file_name().unwrap().to_string_lossy()))
            .collect::<String>(),
    )
    .unwrap();
    let mut reports = Vec::new();
    let mut names = Vec::new();
    for i in 0..3 {
        let out = d.join(format!("shard{i}"));
        let mut args = fit_args(&atlas, &list, &out);
        args.extend(["--shard".into(), format!("{i}/3")]);
        // With the pages (the shards' parameters must match to merge).
        args.retain(|a| a != "--no-plots");
        let o = atlasmesh(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let r = report(&out);
        assert_eq!(r.shard.as_deref(), Some(format!("{i}/3").as_str()));
        // The atlas named with its checksum, in the report and on its page's title.
        let a = r.atlas.as_ref().expect("the atlas in report.json");
        assert_eq!(a.file, s(&atlas));
        let crc = crc32fast::hash(&std::fs::read(&atlas).unwrap());
        assert_eq!(a.checksum_crc32, format!("{crc:08x}"));
        if i == 0 {
            let page = std::fs::read_to_string(out.join("report.html")).unwrap();
            let name = atlas.file_name().unwrap().to_string_lossy().to_string();
            let n = r.subjects.len();
            let title = format!("<h1>atlasmesh fit: {n} subjects with the atlas {name}</h1>");
            assert!(page.contains(&title), "{title}");
            assert!(page.contains(&format!("(CRC-32 {})", a.checksum_crc32)));
        }
        names.extend(r.subjects.iter().map(|s| s.name.clone()));
        reports.push(s(&out.join("report.json")));
    }
    let n = names.len();
    names.sort();
    names.dedup();
    assert_eq!(names.len(), n, "shards are disjoint");
    assert_eq!(n, 7, "shards cover the list");
    let merged = d.join("merged.json");
    let mut args = vec!["merge-reports".to_string()];
    args.extend(reports.iter().cloned());
    args.extend(["--out".into(), s(&merged)]);
    let o = atlasmesh(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let m: atlasmesh::report::Report =
        serde_json::from_slice(&std::fs::read(&merged).unwrap()).unwrap();
    assert_eq!(m.summary.subjects, 7);
    assert_eq!(m.atlas, report(&d.join("shard0")).atlas);
    assert_eq!(
        m.subjects
            .iter()
            .map(|s| s.name.clone())
            .collect::<Vec<_>>(),
        names
    );
    // The run's shape scores beside the merged report: a row per subject, as the shards had.
    let scores = std::fs::read_to_string(d.join("merged.scores.csv")).unwrap();
    let rows: Vec<&str> = scores.lines().collect();
    assert_eq!(rows.len(), 1 + n, "{scores}");
    assert!(rows[0].starts_with("name,mode_1"), "{}", rows[0]);
    for name in &names {
        assert!(
            rows.iter().any(|r| r.starts_with(&format!("{name},"))),
            "{name}: {scores}"
        );
    }
    // A shard merged twice is refused.
    let mut args = vec!["merge-reports".to_string(), reports[0].clone()];
    args.extend([reports[0].clone(), "--out".into(), s(&d.join("twice.json"))]);
    let o = atlasmesh(&args);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("in two of the reports"));
    // A bad shard spec.
    let mut args = fit_args(&atlas, &list, &d.join("bad"));
    args.extend(["--shard".into(), "3/3".into()]);
    let o = atlasmesh(&args);
    assert_eq!(o.status.code(), Some(2));
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn a_failing_subject_is_reported_and_the_batch_goes_on() {
    let (d, atlas, subjects) = setup("batch-fail", 3);
    // A truncated binary PLY beside the good subjects.
    let bytes = std::fs::read(&subjects[0]).unwrap();
    let bad = subjects[0].with_file_name("truncated.ply");
    std::fs::write(&bad, &bytes[..bytes.len() / 2]).unwrap();
    let out = d.join("out");
    let o = atlasmesh(&fit_args(&atlas, subjects[0].parent().unwrap(), &out));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(6), "some subjects failed: {err}");
    assert!(err.contains("truncated"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    let r = report(&out);
    assert_eq!(r.summary.subjects, 4);
    assert_eq!(r.summary.failed, 1);
    assert_eq!(r.failed[0].name, "truncated");
    assert_eq!(r.failed[0].exit_code, 2);
    assert_eq!(r.subjects.len(), 3);
    assert!(r.subjects.iter().all(|s| s.inverted_elements == 0));
    std::fs::remove_dir_all(&d).ok();
}

/// The test cluster (`scripts/slurm-single-node.sh`, which `.ci/run` starts): its folder (that
/// of `SLURM_CONF`) and a lock on it, so that the tests using it take turns, when its one node
/// answers `idle`; otherwise `None`: the test is skipped, or fails when the tools are required
/// (`ATLASMESH_REQUIRE_TOOLS`). A drained, allocated or silent node is never waited on.
fn cluster(test: &str) -> Option<(PathBuf, std::fs::File)> {
    let required = std::env::var_os("ATLASMESH_REQUIRE_TOOLS").is_some();
    let skip = |why: String| {
        assert!(!required, "{test}: a Slurm cluster is required: {why}");
        common::skipped(
            test,
            &format!("{why}; scripts/slurm-single-node.sh start starts one"),
        );
        None
    };
    let Some(conf) = std::env::var_os("SLURM_CONF").map(PathBuf::from) else {
        return skip("SLURM_CONF is not set".into());
    };
    let dir = conf.parent().unwrap().to_path_buf();
    let Ok(lock) = std::fs::File::create(dir.join("tests.lock")) else {
        return skip(format!("no cluster folder {}", dir.display()));
    };
    // SAFETY: flock(2) on a file this function owns; blocks until the other test is done.
    unsafe {
        use std::os::fd::AsRawFd;
        libc::flock(lock.as_raw_fd(), libc::LOCK_EX);
    }
    let state = common::try_run(
        Command::new("sinfo").args(["-h", "-o", "%T"]),
        common::deadline::SHORT,
    );
    match state {
        Ok(o) if o.status.success() && String::from_utf8_lossy(&o.stdout).trim() == "idle" => {
            Some((dir, lock))
        }
        Ok(o) => skip(format!(
            "its node is not idle: sinfo says {:?} {}",
            String::from_utf8_lossy(&o.stdout).trim(),
            String::from_utf8_lossy(&o.stderr).trim()
        )),
        Err(e) => skip(e),
    }
}

/// The cluster's script, `scripts/slurm-single-node.sh`.
fn cluster_script() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/slurm-single-node.sh")
}

/// Submits a job that sleeps 10 minutes (its limit 5), waits until it runs; its id and the
/// pid of its task.
fn long_job(d: &Path, name: &str) -> (String, u32) {
    let pid_file = d.join(format!("{name}.pid"));
    let o = common::run(
        Command::new("sbatch")
            .args(["--parsable", "--time=5", "--job-name=atlasmesh-test-long"])
            .arg(format!("--chdir={}", d.display()))
            .arg(format!(
                "--output={}",
                d.join(format!("{name}.out")).display()
            ))
            .arg(format!(
                "--wrap=echo $$ > '{}.tmp' && mv '{0}.tmp' '{0}' && exec sleep 600",
                pid_file.display()
            )),
        common::deadline::SHORT,
    );
    assert!(
        o.status.success(),
        "sbatch: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let job = String::from_utf8_lossy(&o.stdout).trim().to_string();
    let t = std::time::Instant::now();
    while !pid_file.is_file() {
        assert!(
            t.elapsed().as_secs() < 60,
            "job {job} did not start in 60 s"
        );
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    let pid = std::fs::read_to_string(&pid_file)
        .unwrap()
        .trim()
        .parse()
        .unwrap();
    assert!(common::alive(pid), "job {job}: its task {pid} does not run");
    (job, pid)
}

/// `scripts/slurm-single-node.sh ACTION` on the cluster folder `dir`.
fn cluster_do(dir: &Path, action: &str) -> std::process::Output {
    common::run(
        Command::new(cluster_script()).arg(action).arg(dir),
        std::time::Duration::from_secs(180),
    )
}

/// The pid in the cluster's pid file `name` (`slurmctld.pid`, `slurmd.pid`).
fn daemon(dir: &Path, name: &str) -> u32 {
    std::fs::read_to_string(dir.join(name))
        .unwrap()
        .trim()
        .parse()
        .unwrap()
}

/// The test cluster starts clean after a run that was killed (its daemons gone, a job's task
/// still running: the task is ended, the job and its node state forgotten), and `stop`
/// cancels a running job, ends its task and every daemon; then the cluster is started again
/// for the other tests.
#[test]
fn the_test_cluster_stops_everything_and_starts_clean() {
    let Some((dir, _lock)) = cluster("Slurm cluster stop and start") else {
        return;
    };
    let d = common::temp_dir("slurm-stop");
    let squeue = || {
        let o = common::run(
            Command::new("squeue").args(["-h", "-o", "%A"]),
            common::deadline::SHORT,
        );
        assert!(
            o.status.success(),
            "squeue: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        String::from_utf8_lossy(&o.stdout).trim().to_string()
    };
    // A run killed with a job running: its controller and node daemon die, the task lives on.
    let (job, task) = long_job(&d, "left");
    for f in ["slurmctld.pid", "slurmd.pid"] {
        // SAFETY: kill(2) of a daemon of this test cluster, by the pid it wrote.
        unsafe {
            libc::kill(daemon(&dir, f) as libc::pid_t, libc::SIGKILL);
        }
    }
    std::thread::sleep(std::time::Duration::from_millis(300));
    assert!(
        common::alive(task),
        "the left task should outlive its daemons"
    );
    let o = cluster_do(&dir, "start");
    assert!(
        o.status.success(),
        "start: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert_eq!(
        String::from_utf8_lossy(&o.stdout).trim(),
        dir.join("slurm.conf").display().to_string()
    );
    assert!(
        !common::alive(task),
        "start left the earlier run's task {task} running"
    );
    assert_eq!(squeue(), "", "start: jobs of the earlier run came back");
    let o = common::run(
        Command::new("scontrol").args(["show", "job", &job]),
        common::deadline::SHORT,
    );
    assert!(
        !o.status.success() && String::from_utf8_lossy(&o.stderr).contains("Invalid job id"),
        "job {job} of the earlier run is known: {}",
        String::from_utf8_lossy(&o.stdout)
    );
    // stop: the job cancelled, its task and every daemon ended.
    let (_, task) = long_job(&d, "stopped");
    let (ctld, slurmd) = (daemon(&dir, "slurmctld.pid"), daemon(&dir, "slurmd.pid"));
    let o = cluster_do(&dir, "stop");
    assert!(
        o.status.success(),
        "stop: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    for (what, pid) in [
        ("the job's task", task),
        ("slurmctld", ctld),
        ("slurmd", slurmd),
    ] {
        assert!(!common::alive(pid), "stop left {what} ({pid}) running");
    }
    let o = cluster_do(&dir, "status");
    let said = String::from_utf8_lossy(&o.stdout);
    assert!(!o.status.success(), "status after stop: {said}");
    assert!(said.contains("step daemons: none"), "{said}");
    // Started again for the array job.
    let o = cluster_do(&dir, "start");
    assert!(
        o.status.success(),
        "start: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert_eq!(squeue(), "");
}

/// The shipped Slurm array script (`scripts/atlasmesh-array.sbatch`) through a real cluster
/// (`scripts/slurm-single-node.sh start` starts one; `.ci/run` does): three array tasks, one
/// shard each, then `merge-reports`. The job has a time limit and the test its own deadline;
/// on a failure the job is cancelled and its logs printed.
#[test]
fn a_slurm_array_job_fits_the_shards() {
    let Some((_cluster, _lock)) = cluster("Slurm array job") else {
        return;
    };
    let (d, atlas, subjects) = setup("batch-slurm", 7);
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/atlasmesh-array.sbatch");
    let out = d.join("out");
    let name = format!("atlasmesh-test-array-{}", std::process::id());
    let o = common::try_run(
        Command::new("sbatch")
            .args(["--wait", "--array=0-2", "--mem=500M", "--time=10"])
            .arg(format!("--job-name={name}"))
            .arg(format!("--chdir={}", d.display()))
            .arg(&script)
            .arg(&atlas)
            .arg(subjects[0].parent().unwrap())
            .arg(&out)
            .env("ATLASMESH", env!("CARGO_BIN_EXE_atlasmesh")),
        std::time::Duration::from_secs(12 * 60),
    );
    let logs = || -> String {
        std::fs::read_dir(&d)
            .unwrap()
            .flatten()
            .filter(|e| e.file_name().to_string_lossy().ends_with(".log"))
            .map(|e| std::fs::read_to_string(e.path()).unwrap_or_default())
            .collect()
    };
    let failure = match &o {
        Ok(o) if o.status.success() => None,
        Ok(o) => Some(format!(
            "sbatch: {}{}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        )),
        Err(e) => Some(e.clone()),
    };
    if let Some(f) = failure {
        let _ = common::try_run(
            Command::new("scancel").arg(format!("--name={name}")),
            common::deadline::SHORT,
        );
        panic!("{f}\njob logs:\n{}", logs());
    }
    let mut args = vec!["merge-reports".to_string()];
    for i in 0..3 {
        let r = out.join(format!("shard-{i}/report.json"));
        assert!(r.is_file(), "task {i} wrote no report: {}", logs());
        args.push(s(&r));
    }
    args.extend(["--out".into(), s(&out.join("report.json"))]);
    let o = atlasmesh(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r = report(&out);
    assert_eq!(r.summary.subjects, 7);
    assert_eq!(r.summary.meshes_valid, 7);
}
