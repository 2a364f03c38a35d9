//! Shared helpers of the integration tests.

use std::path::PathBuf;

/// The data folder named by `ATLASMESH_DATA`, or `None` (the test prints that it was skipped).
/// When the variable is set, a missing folder is a failure.
pub fn data_dir(test: &str) -> Option<PathBuf> {
    match std::env::var_os("ATLASMESH_DATA") {
        None => {
            eprintln!("{test}: skipped (ATLASMESH_DATA is not set)");
            None
        }
        Some(d) => {
            let p = PathBuf::from(d);
            assert!(p.is_dir(), "ATLASMESH_DATA={} is not a folder", p.display());
            Some(p)
        }
    }
}

/// A fresh temporary folder for one test.
pub fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("atlasmesh-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
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
        eprintln!("{what}: skipped ({program} not found)");
    }
    ok
}

/// A CalculiX step around a mesh deck: bone-like elasticity, `FIXED` clamped, a unit force
/// along -z on every node of `LOAD`, displacements of `LOAD` printed to the `.dat` file.
pub const CCX_STEP: &str = "*MATERIAL, NAME=TISSUE
*ELASTIC
17000., 0.3
*SOLID SECTION, ELSET=EALL, MATERIAL=TISSUE
*STEP
*STATIC
*BOUNDARY
FIXED, 1, 3, 0.
*CLOAD
LOAD, 3, -1.
*NODE PRINT, NSET=LOAD
U
*END STEP
";

/// Runs ccx on `deck` (a `.inp` path) in its folder; returns the displacements it printed.
pub fn solve(deck: &std::path::Path) -> Vec<[f64; 3]> {
    let dir = deck.parent().unwrap();
    let stem = deck.file_stem().unwrap().to_string_lossy().to_string();
    let o = std::process::Command::new("ccx")
        .arg("-i")
        .arg(&stem)
        .current_dir(dir)
        .output()
        .unwrap();
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
    std::process::Command::new(env!("CARGO_BIN_EXE_atlasmesh"))
        .args(args)
        .arg("--quiet")
        .output()
        .unwrap()
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
            eprintln!("meshio checks: skipped (ATLASMESH_PYTHON is not set)");
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
    let o = std::process::Command::new(py)
        .arg("-c")
        .arg(script)
        .args(files)
        .output()
        .unwrap();
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
