//! Shared helpers of the integration tests.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// Says that `what` was skipped and why, on the terminal: written to the standard error
/// itself, not through `eprintln!`, which the test harness keeps to itself for tests that
/// pass, so that a run without data or tools shows what it did not check among its `ok`s.
pub fn skipped(what: &str, why: &str) {
    use std::io::Write;
    let _ = writeln!(std::io::stderr(), "skipped: {what} ({why})");
}

/// The data folder named by `ATLASMESH_DATA`, or `None` (the test says it was skipped:
/// [`skipped`]). When the variable is set, a missing folder is a failure.
pub fn data_dir(test: &str) -> Option<PathBuf> {
    match std::env::var_os("ATLASMESH_DATA") {
        None => {
            skipped(test, "ATLASMESH_DATA is not set");
            None
        }
        Some(d) => {
            let p = PathBuf::from(d);
            assert!(p.is_dir(), "ATLASMESH_DATA={} is not a folder", p.display());
            Some(p)
        }
    }
}

/// A fresh temporary folder for one test, `atlasmesh-NAME-XXXXXX` in the system's temporary
/// directory, removed with everything in it when the guard is dropped, whether the test passed
/// or failed. `ATLASMESH_KEEP_TMP=1` keeps it (its path is printed) to look at a failure.
pub fn temp_dir(name: &str) -> TempDir {
    let keep = std::env::var_os("ATLASMESH_KEEP_TMP").is_some_and(|v| !v.is_empty() && v != "0");
    let dir = tempfile::Builder::new()
        .prefix(&format!("atlasmesh-{name}-"))
        .disable_cleanup(keep)
        .tempdir()
        .unwrap();
    if keep {
        eprintln!("{name}: files kept in {}", dir.path().display());
    }
    TempDir(dir)
}

/// A test's temporary folder ([`temp_dir`]): a path, removed on drop.
#[derive(Debug)]
pub struct TempDir(tempfile::TempDir);

impl std::ops::Deref for TempDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        self.0.path()
    }
}

impl AsRef<Path> for TempDir {
    fn as_ref(&self) -> &Path {
        self.0.path()
    }
}

impl AsRef<std::ffi::OsStr> for TempDir {
    fn as_ref(&self) -> &std::ffi::OsStr {
        self.0.path().as_os_str()
    }
}

/// Deadlines of the external programs the tests run ([`run`]): a hang fails its test with
/// the program's output instead of holding the suite.
pub mod deadline {
    use std::time::Duration;
    /// The command-line tool on the largest data of a test (a leave-one-out of femurs).
    pub const ATLASMESH: Duration = Duration::from_secs(20 * 60);
    /// Headless Chromium opening one page (known to hang at exit now and then).
    pub const CHROMIUM: Duration = Duration::from_secs(120);
    /// CalculiX solving one deck.
    pub const CCX: Duration = Duration::from_secs(600);
    /// Gmsh checking or meshing one file.
    pub const GMSH: Duration = Duration::from_secs(120);
    /// One Python script (meshio, PyVista, nibabel, SimpleITK, pydicom).
    pub const PYTHON: Duration = Duration::from_secs(600);
    /// A shell utility (`mkfifo`, `sinfo`, `squeue`, `scancel`).
    pub const SHORT: Duration = Duration::from_secs(60);
}

/// Runs `cmd` to its end or its `deadline`, with its standard input empty and its output
/// captured; panics, with the command and what it printed, when it could not start or ran
/// past its deadline ([`try_run`]).
pub fn run(cmd: &mut Command, deadline: Duration) -> Output {
    try_run(cmd, deadline).unwrap_or_else(|e| panic!("{e}"))
}

/// [`run`], with the reason as an error: `cmd` runs in a process group of its own; at the
/// deadline the whole group (the program and every child it started) is killed; after the
/// program exits, whatever it left running in its group is killed too, so that nothing a test
/// started outlives it.
pub fn try_run(cmd: &mut Command, deadline: Duration) -> Result<Output, String> {
    use std::io::Read;
    use std::os::unix::process::CommandExt;
    use std::sync::{Arc, Mutex};
    let what = describe(cmd);
    let mut child = cmd
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .process_group(0)
        .spawn()
        .map_err(|e| format!("{what}: could not start: {e}"))?;
    let group = child.id() as libc::pid_t;
    // Readers fill shared buffers, so that what was printed is there even when a process
    // outside the group keeps a pipe open.
    let reader = |mut pipe: Box<dyn Read + Send>| {
        let buf = Arc::new(Mutex::new(Vec::new()));
        let b = Arc::clone(&buf);
        let handle = std::thread::spawn(move || {
            let mut chunk = [0u8; 8192];
            while let Ok(n) = pipe.read(&mut chunk) {
                if n == 0 {
                    break;
                }
                b.lock().unwrap().extend_from_slice(&chunk[..n]);
            }
        });
        (buf, handle)
    };
    let (out, out_reader) = reader(Box::new(child.stdout.take().unwrap()));
    let (err, err_reader) = reader(Box::new(child.stderr.take().unwrap()));
    let start = Instant::now();
    let mut timed_out = false;
    let status = loop {
        match child.try_wait() {
            Ok(Some(status)) => break status,
            Ok(None) if start.elapsed() >= deadline => {
                timed_out = true;
                kill_group(group);
                break child.wait().map_err(|e| format!("{what}: {e}"))?;
            }
            Ok(None) => std::thread::sleep(Duration::from_millis(
                (start.elapsed().as_millis() as u64 / 10).clamp(2, 50),
            )),
            Err(e) => return Err(format!("{what}: {e}")),
        }
    };
    kill_group(group);
    let drained = Instant::now();
    while !(out_reader.is_finished() && err_reader.is_finished())
        && drained.elapsed() < Duration::from_secs(5)
    {
        std::thread::sleep(Duration::from_millis(5));
    }
    let stdout = std::mem::take(&mut *out.lock().unwrap());
    let stderr = std::mem::take(&mut *err.lock().unwrap());
    if timed_out {
        return Err(format!(
            "{what}: killed at its deadline of {} s (with its process group)\n--- stdout (end) ---\n{}\n--- stderr (end) ---\n{}",
            deadline.as_secs_f64(),
            tail(&stdout),
            tail(&stderr)
        ));
    }
    Ok(Output {
        status,
        stdout,
        stderr,
    })
}

/// Whether the process `pid` runs (a zombie, ended but not yet reaped, does not).
#[allow(dead_code)]
pub fn alive(pid: u32) -> bool {
    std::fs::read_to_string(format!("/proc/{pid}/status")).is_ok_and(|s| {
        !s.lines()
            .any(|l| l.starts_with("State:") && l.contains('Z'))
    })
}

/// SIGKILL to every process of the group `group` (none left is fine).
fn kill_group(group: libc::pid_t) {
    // SAFETY: kill(2) with a negative pid signals a process group; no memory is involved.
    unsafe {
        libc::kill(-group, libc::SIGKILL);
    }
}

/// The program and its arguments, cut to a readable length.
fn describe(cmd: &Command) -> String {
    let mut s = cmd.get_program().to_string_lossy().into_owned();
    for a in cmd.get_args() {
        s.push(' ');
        s.push_str(&a.to_string_lossy());
    }
    if s.len() > 300 {
        let cut = (0..=300)
            .rev()
            .find(|&i| s.is_char_boundary(i))
            .unwrap_or(0);
        s.truncate(cut);
        s.push_str(" …");
    }
    s
}

/// The last 4000 bytes of a program's output, as text.
fn tail(bytes: &[u8]) -> String {
    let from = bytes.len().saturating_sub(4000);
    String::from_utf8_lossy(&bytes[from..]).into_owned()
}

/// The 40 IMM hands of `data`, resampled in correspondence to 2001 points (`Some`) or as
/// given (56 landmarks, `None`); open outlines.
pub fn hands(
    data: &std::path::Path,
    resample: Option<usize>,
) -> Vec<atlasmesh::geometry::Shape<2>> {
    atlasmesh::study::load_population(
        &[data.join("imm-hands-2d/hands_long.csv")],
        &atlasmesh::study::PopulationOptions {
            closed: false,
            resample,
            ..Default::default()
        },
    )
    .unwrap()
}

/// The distal femurs S001-S030 of `data`.
pub fn femurs(data: &std::path::Path) -> Vec<atlasmesh::geometry::Shape<3>> {
    let paths: Vec<_> = (1..=30)
        .map(|k| {
            data.join(format!(
                "knee-distal-femur-synthetic-3d/femur/S{k:03}_Femur.ply"
            ))
        })
        .collect();
    atlasmesh::study::load_surfaces(&paths, &Default::default()).unwrap()
}

pub use crate::raw_femurs::{FEMUR_LANDMARKS, raw_femurs};

/// Whether `program` is an executable on the `PATH` (or, with a `/`, that file); a failure
/// when the tools are required. The program is not run: CalculiX takes any argument, even
/// `--version`, as the name of a job and writes its output files for it.
pub fn tool(program: &str, what: &str) -> bool {
    use std::os::unix::fs::PermissionsExt;
    let executable = |p: &std::path::Path| {
        p.metadata()
            .is_ok_and(|m| m.is_file() && m.permissions().mode() & 0o111 != 0)
    };
    let ok = if program.contains('/') {
        executable(std::path::Path::new(program))
    } else {
        std::env::var_os("PATH")
            .is_some_and(|path| std::env::split_paths(&path).any(|d| executable(&d.join(program))))
    };
    if !ok {
        assert!(
            std::env::var_os("ATLASMESH_REQUIRE_TOOLS").is_none(),
            "{program} is required ({what}) but not found"
        );
        skipped(what, &format!("{program} not found"));
    }
    ok
}

/// A CalculiX step around a mesh deck: bone-like elasticity, `FIXED` clamped, a unit force
/// along -z on every node of `LOAD`, displacements of `LOAD` printed to the `.dat` file.
/// (tests/fixtures/ccx_step.inp, which the Python tests read too.)
pub const CCX_STEP: &str = include_str!("../fixtures/ccx_step.inp");

/// Runs ccx on `deck` (a `.inp` path) in its folder; returns the displacements it printed.
pub fn solve(deck: &std::path::Path) -> Vec<[f64; 3]> {
    let dir = deck.parent().unwrap();
    let stem = deck.file_stem().unwrap().to_string_lossy().to_string();
    let o = run(
        Command::new("ccx").arg("-i").arg(&stem).current_dir(dir),
        deadline::CCX,
    );
    let log = String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "ccx on {stem}: {log}");
    assert!(!log.contains("*ERROR"), "ccx on {stem}: {log}");
    let dat = std::fs::read_to_string(dir.join(format!("{stem}.dat"))).unwrap();
    let body = dat
        .split("displacements (vx,vy,vz)")
        .nth(1)
        .expect("displacements in the .dat file");
    body.lines()
        .skip(1)
        .filter_map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            (f.len() == 4).then(|| std::array::from_fn(|d| f[d + 1].parse::<f64>().unwrap()))
        })
        .collect()
}

/// Morphs and repairs the mean mesh of `atlas` to the instances at ±3σ along the first 5
/// modes; returns per instance (mode, sign, min scaled Jacobian before, after, inverted
/// after, boundary distance change / median edge).
pub fn stress<const D: usize>(
    atlas: &atlasmesh::model::Atlas<D>,
) -> Vec<(usize, f64, f64, f64, usize, f64)> {
    let morpher = atlas
        .morpher(&atlasmesh::ffd::FfdParams::default())
        .unwrap();
    let edge = atlas.mean_shape().median_edge_length();
    let mut rows = Vec::new();
    for m in 0..5.min(atlas.num_modes()) {
        for sign in [-3.0, 3.0] {
            let mut w = vec![0.0; atlas.num_modes()];
            w[m] = sign * atlas.eigenvalues[m].sqrt();
            let instance = atlas.instance(&w);
            let shape = atlasmesh::geometry::Shape {
                name: format!("mode{m}{sign:+}"),
                points: instance.clone(),
                facets: atlas.facets.clone(),
                landmarks: Vec::new(),
            };
            let index = atlasmesh::geometry::ClosestPointIndex::from_shape(&shape);
            let fit = atlasmesh::fit::FitResult {
                weights: w,
                similarity: atlasmesh::geometry::Similarity::identity(),
                instance: instance.clone(),
                projected: instance
                    .iter()
                    .map(|p| atlasmesh::geometry::SurfacePoint {
                        point: *p,
                        facet: 0,
                        weights: [0.0; D],
                        dist2: 0.0,
                        slot: u32::MAX,
                    })
                    .collect(),
                corresponded: vec![true; instance.len()],
                e_d_history: Vec::new(),
                locus: Vec::new(),
                iterations: 0,
                converged: true,
            };
            let morph = morpher.morph(&fit.correspondence()).unwrap();
            let mut mesh = morph.mesh;
            let (r, _) = atlasmesh::mesh::repair::repair_with_quality(
                &mut mesh,
                Some(&index),
                &atlasmesh::mesh::repair::RepairParams::default(),
                &morph.quality,
            )
            .unwrap();
            rows.push((
                m,
                sign,
                r.scaled_jacobian_min_before,
                r.scaled_jacobian_min,
                r.inverted_after,
                r.surface_distance_change / edge,
            ));
        }
    }
    rows
}

pub fn check(name: &str, rows: &[(usize, f64, f64, f64, usize, f64)], bound: f64) {
    let needed = rows.iter().filter(|r| r.2 < bound).count();
    for r in rows {
        eprintln!(
            "{name} mode {} at {:+}σ: min scaled Jacobian {:.3} -> {:.3}, inverted {}, boundary change {:.2e} edges",
            r.0 + 1,
            r.1,
            r.2,
            r.3,
            r.4,
            r.5
        );
    }
    eprintln!("{name}: {needed} of {} meshes needed repair", rows.len());
    for r in rows {
        assert_eq!(
            r.4,
            0,
            "{name} mode {} {:+}: inverted elements",
            r.0 + 1,
            r.1
        );
        assert!(
            r.3 >= r.2.min(bound) - 1e-12,
            "{name}: the repair made it worse"
        );
        assert!(r.5 <= 0.01, "{name}: boundary moved {} edges off", r.5);
        assert!(
            r.3 >= bound,
            "{name} mode {} {:+}: min scaled Jacobian {} below {bound}",
            r.0 + 1,
            r.1,
            r.3
        );
    }
}

/// Issue 6 on a `loo` report: every mesh valid and at or above its repair bound, the repair's
/// boundary within 1 % of the median edge length off the subject; prints how many needed it.
#[allow(dead_code)]
pub fn assert_repaired(name: &str, r: &atlasmesh::report::Report) {
    let needed: Vec<&atlasmesh::report::SubjectReport> =
        r.subjects.iter().filter(|s| s.repaired).collect();
    eprintln!(
        "{name}: {} of {} meshes needed repair",
        needed.len(),
        r.subjects.len()
    );
    for s in &needed {
        eprintln!(
            "  {}: min scaled Jacobian {:.3} ({} inverted) -> {:.3}, boundary change {:.1e} edges",
            s.name,
            s.scaled_jacobian_min_before_repair,
            s.inverted_before_repair,
            s.scaled_jacobian_min,
            s.surface_distance_change_edges
        );
    }
    for s in &r.subjects {
        assert!(s.repair_bound > 0.0, "{name} {}: repair off", s.name);
        assert_eq!(s.inverted_elements, 0, "{name} {}: inverted", s.name);
        assert!(
            s.scaled_jacobian_min >= s.repair_bound,
            "{name} {}: min scaled Jacobian {} below {}",
            s.name,
            s.scaled_jacobian_min,
            s.repair_bound
        );
        assert!(
            s.surface_distance_change_edges <= 0.01,
            "{name} {}: boundary moved {} edges off",
            s.name,
            s.surface_distance_change_edges
        );
    }
    assert_eq!(r.summary.below_repair_bound, 0);
}

/// Runs the command-line tool with `args` and `--quiet`.
#[allow(dead_code)]
pub fn atlasmesh<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> std::process::Output {
    run(
        Command::new(env!("CARGO_BIN_EXE_atlasmesh"))
            .args(args)
            .arg("--quiet"),
        deadline::ATLASMESH,
    )
}

/// The Python with meshio named by `ATLASMESH_PYTHON`, or `None` (the check is skipped with a
/// message); with `ATLASMESH_REQUIRE_TOOLS` set, a missing one is a failure.
#[allow(dead_code)]
pub fn python() -> Option<PathBuf> {
    match std::env::var_os("ATLASMESH_PYTHON") {
        Some(p) => Some(PathBuf::from(p)),
        None => {
            assert!(
                std::env::var_os("ATLASMESH_REQUIRE_TOOLS").is_none(),
                "ATLASMESH_PYTHON (a Python with meshio) is required"
            );
            skipped("meshio checks", "ATLASMESH_PYTHON is not set");
            None
        }
    }
}

/// A mesh as meshio reads it: its points and the cells of its first block.
pub type MeshioMesh = (Vec<Vec<f64>>, Vec<Vec<usize>>);

/// The meshes of `files` as meshio reads them (one Python run for all), or `None` without a
/// Python with meshio.
#[allow(dead_code)]
pub fn meshio_meshes(files: &[PathBuf]) -> Option<Vec<MeshioMesh>> {
    let py = python()?;
    let script = r#"
import sys, json, meshio
out = []
for f in sys.argv[1:]:
    m = meshio.read(f)
    out.append([m.points.tolist(), m.cells[0].data.tolist()])
print(json.dumps(out))
"#;
    let o = run(
        Command::new(py).arg("-c").arg(script).args(files),
        deadline::PYTHON,
    );
    assert!(
        o.status.success(),
        "meshio: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    Some(serde_json::from_slice(&o.stdout).unwrap())
}

/// Every subject of `r` that reports `success` delivered what it claims: its mesh file
/// (`NAME_mesh.vtu` in `out`), read back by meshio (when there is a Python with it; its
/// nodes and cells must be those atlasmesh reads), has no inverted element and no non-finite
/// node, and
/// its boundary lies within the run's bound (`max_mesh_distance` of the subject's diagonal,
/// two-way RMS; subject → mesh only for open outlines and partial fits) of the subject (found
/// by name in `subjects`); the distance read back is the one reported. Returns how many were
/// checked.
#[allow(dead_code)]
pub fn assert_delivered<const D: usize>(
    r: &atlasmesh::report::Report,
    out: &std::path::Path,
    subjects: &[atlasmesh::geometry::Shape<D>],
) -> usize {
    use atlasmesh::eval::surface_distances;
    use atlasmesh::geometry::ClosestPointIndex;
    use atlasmesh::mesh::{boundary_surface, mesh_quality, summarize};
    let bound = r.parameters["max_mesh_distance"].as_f64().unwrap();
    let partial = r.parameters["fit"]["partial"].as_bool().unwrap_or(false);
    let mut checked = 0;
    let successes: Vec<&atlasmesh::report::SubjectReport> =
        r.subjects.iter().filter(|s| s.success).collect();
    let files: Vec<PathBuf> = successes
        .iter()
        .map(|s| {
            let f = s
                .files
                .iter()
                .find(|f| f.ends_with("_mesh.vtu"))
                .unwrap_or_else(|| panic!("{}: no mesh file in {:?}", s.name, s.files));
            out.join(f)
        })
        .collect();
    let by_meshio = meshio_meshes(&files);
    for (k, s) in successes.into_iter().enumerate() {
        let subject = subjects
            .iter()
            .find(|x| x.name == s.name)
            .unwrap_or_else(|| panic!("{}: no such subject", s.name));
        let mesh: atlasmesh::mesh::FeMesh<D> = atlasmesh::formats::read_fe_mesh(&files[k]).unwrap();
        if let Some(m) = &by_meshio {
            let (points, cells) = &m[k];
            assert_eq!(
                points.len(),
                mesh.nodes.len(),
                "{}: meshio's node count",
                s.name
            );
            for (p, q) in points.iter().zip(&mesh.nodes) {
                assert!(
                    (0..D).all(|d| (p[d] - q[d]).abs() <= 1e-9 * (1.0 + q[d].abs())),
                    "{}: meshio reads node {p:?}, atlasmesh {q:?}",
                    s.name
                );
            }
            let connectivity: Vec<usize> = cells.iter().flatten().copied().collect();
            assert_eq!(
                connectivity, mesh.connectivity,
                "{}: meshio's cells",
                s.name
            );
        }
        assert!(
            mesh.nodes.iter().flatten().all(|v| v.is_finite()),
            "{}: non-finite node",
            s.name
        );
        assert_eq!(
            summarize(&mesh_quality(&mesh)).inverted_elements,
            0,
            "{}: success with an inverted element",
            s.name
        );
        let boundary = boundary_surface(&mesh);
        let index = ClosestPointIndex::from_shape(subject);
        let open = D == 2 && subject.facets.len() < subject.points.len();
        let two_way = !(partial || open);
        let d = surface_distances(&boundary, subject, &index, two_way, 1.0);
        let rel = d.rms / subject.bbox_diagonal();
        assert!(
            rel <= bound,
            "{}: success, but the mesh written is {:.4} (RMS, {:.2} % of the diagonal) from the subject",
            s.name,
            d.rms,
            100.0 * rel
        );
        assert!(
            (d.rms - s.mesh_rms_distance).abs() <= 1e-6 * (1.0 + d.rms),
            "{}: reported mesh distance {} but the file is at {}",
            s.name,
            s.mesh_rms_distance,
            d.rms
        );
        checked += 1;
    }
    checked
}
