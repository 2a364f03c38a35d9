//! `atlasmesh instance` as users run it: a sweep of the first mode, each instance's surface
//! and FE mesh in the data's unit, every mesh valid and close to its surface, read back by
//! atlasmesh and by meshio (when there is a Python with it).

use crate::bad_input::{atlas_2d, fails, files_in};
use crate::common::{self, atlasmesh};
use std::path::{Path, PathBuf};

fn s(p: &Path) -> String {
    p.display().to_string()
}

fn read_report(out: &Path) -> atlasmesh::report::InstancesReport {
    serde_json::from_slice(&std::fs::read(out.join("instances.json")).unwrap()).unwrap()
}

/// Every `href` of an HTML page names a file that exists beside it.
fn links_resolve(html: &str, dir: &Path) {
    let links: Vec<&str> = html
        .split("href=\"")
        .skip(1)
        .map(|r| &r[..r.find('"').unwrap()])
        .collect();
    assert!(!links.is_empty());
    for l in links {
        assert!(dir.join(l).is_file(), "link {l} of {}", dir.display());
    }
}

#[test]
fn a_sweep_of_the_first_mode_gives_valid_meshes_in_the_data_unit() {
    let d = common::temp_dir("instance-sweep");
    let atlas = atlas_2d(&d);
    // `atlasmesh instance --atlas ATLAS ARGS --out OUT`.
    let run = |args: &[&str], out: &Path| {
        let (a, o) = (s(&atlas), s(out));
        let mut all = vec!["instance", "--atlas", &a];
        all.extend_from_slice(args);
        all.extend(["--out", &o]);
        atlasmesh(&all)
    };
    let out = d.join("sweep");
    let o = run(
        &["--mode", "1", "--steps", "-3:3:1", "--format", "vtu,inp"],
        &out,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let report = read_report(&out);
    let reports = &report.instances;
    assert_eq!(reports.len(), 7);
    assert!(report.data_unit && report.sampling.is_none());
    // The page, with a picture per instance (plots are on by default), links that resolve.
    let html = std::fs::read_to_string(out.join("instances.html")).unwrap();
    assert_eq!(html.matches("<img class=\"thumb\"").count(), 7);
    links_resolve(&html, &out);
    // The population's size (the demo outlines are about 2 units across).
    let pop = atlasmesh::study::demo_population(12, 120, 5);
    let size = |pts: &[[f64; 2]]| {
        let (lo, hi) = atlasmesh::geometry::bounding_box(pts);
        (hi[0] - lo[0]).max(hi[1] - lo[1])
    };
    let pop_size = pop.iter().map(|s| size(&s.points)).sum::<f64>() / pop.len() as f64;
    let mut mesh_files: Vec<PathBuf> = Vec::new();
    let mut read: Vec<atlasmesh::mesh::FeMesh<2>> = Vec::new();
    for r in reports {
        assert_eq!(r.inverted_elements, 0, "{}", r.name);
        assert_eq!(r.elements_below_repair_bound, 0, "{}", r.name);
        // The morph puts the boundary nodes on the instance's outline as closely as the mean
        // mesh's are on the mean's (the quadrilateral mesher's boundary is a few % of an
        // element off the outline's polyline): within 1 % of the element size more.
        let at_mean = reports.iter().find(|r| r.sd == [0.0]).unwrap();
        assert!(
            r.boundary_node_rms_distance / r.element_size
                < at_mean.boundary_node_rms_distance / at_mean.element_size + 0.01,
            "{}: boundary nodes at {} (RMS) for elements of {}",
            r.name,
            r.boundary_node_rms_distance,
            r.element_size
        );
        assert!(
            r.scaled_jacobian_min > 0.2,
            "{}: {}",
            r.name,
            r.scaled_jacobian_min
        );
        // The boundary follows the instance's outline: the chordal error of elements of that
        // size on the outline's curvature is a few % of the element size.
        assert!(
            r.mesh_rms_distance < 0.1 * r.element_size,
            "{}: RMS {} for elements of {}",
            r.name,
            r.mesh_rms_distance,
            r.element_size
        );
        let base = out.join(&r.name);
        for ext in ["inp", "vtu"] {
            let f = base.join(format!("{}_mesh.{ext}", r.name));
            let mesh: atlasmesh::mesh::FeMesh<2> = atlasmesh::formats::read_fe_mesh(&f).unwrap();
            let q =
                atlasmesh::mesh::quality::summarize(&atlasmesh::mesh::quality::mesh_quality(&mesh));
            assert_eq!(q.inverted_elements, 0, "{}", f.display());
            let checked = atlasmesh(&["quality", &s(&f)]);
            assert!(
                checked.status.success(),
                "{}",
                String::from_utf8_lossy(&checked.stdout)
            );
            mesh_files.push(f);
            read.push(mesh);
        }
        let outline =
            atlasmesh::formats::read_outlines(&base.join(format!("{}.vtp", r.name)), true)
                .unwrap()
                .remove(0);
        let e = size(&outline.points);
        assert!(
            e > 0.7 * pop_size && e < 1.3 * pop_size,
            "{}: extent {e}, population {pop_size}",
            r.name
        );
    }
    // meshio reads every mesh with the nodes and cells atlasmesh reads.
    if let Some(meshes) = common::meshio_meshes(&mesh_files) {
        for ((f, m), (points, cells)) in mesh_files.iter().zip(&read).zip(meshes) {
            assert_eq!(points.len(), m.nodes.len(), "{}", f.display());
            assert_eq!(cells.len(), m.num_elements(), "{}", f.display());
            for (p, q) in points.iter().zip(&m.nodes) {
                assert!((p[0] - q[0]).abs() + (p[1] - q[1]).abs() < 1e-9);
            }
        }
    }
    // The weight 0 is the mean, named as such.
    let mean = reports
        .iter()
        .find(|r| r.sd == [0.0])
        .expect("the weight 0");
    assert_eq!(mean.name, "mode1_0");
    // Bad weights and steps: nothing written.
    let bad = d.join("bad");
    fails(
        &run(&["--weights", "9=1"], &bad),
        2,
        &["9 weights for a model of 4 modes"],
    );
    assert!(files_in(&bad).is_empty() && !bad.exists());
    fails(
        &run(&["--mode", "1", "--steps", "3:1:1"], &bad),
        2,
        &["--steps"],
    );
    // Given weights.
    let o = run(&["--weights", "1=+2,3=-1.5"], &bad);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        bad.join("mode1_plus2_mode3_minus1.5/mode1_plus2_mode3_minus1.5_mesh.vtu")
            .is_file()
    );
}

#[test]
fn a_sampled_population_is_reproducible_resumable_and_shardable() {
    let d = common::temp_dir("sample-2d");
    let atlas = atlas_2d(&d);
    let sample = |args: &[&str], out: &Path| {
        let (a, o) = (s(&atlas), s(out));
        let mut all = vec!["sample", "--atlas", &a, "--n", "9"];
        if !args.contains(&"--seed") {
            all.extend(["--seed", "5"]);
        }
        all.extend_from_slice(args);
        all.extend(["--out", &o, "--no-plots"]);
        atlasmesh(&all)
    };
    let whole = d.join("whole");
    let o = sample(&["--max-sd", "2"], &whole);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r = read_report(&whole);
    assert_eq!(r.instances.len(), 9);
    assert_eq!(r.summary.failed, 0);
    assert_eq!(
        r.sampling,
        Some(atlasmesh::report::Sampling {
            n: 9,
            seed: 5,
            max_sd: Some(2.0)
        })
    );
    for i in &r.instances {
        assert_eq!(i.sd.len(), r.modes, "{}", i.name);
        assert!(i.sd.iter().all(|v| v.abs() <= 2.0 + 1e-9), "{:?}", i.sd);
        assert_eq!(i.inverted_elements, 0);
        assert!(
            whole
                .join(&i.name)
                .join(format!("{}_mesh.vtu", i.name))
                .is_file()
        );
    }
    // Different weights for each sample, not all on one side.
    let first: Vec<f64> = r.instances.iter().map(|i| i.sd[0]).collect();
    assert!(first.iter().any(|&v| v > 0.0) && first.iter().any(|&v| v < 0.0));
    // A re-run makes nothing again and reports the same.
    let o = sample(&["--max-sd", "2"], &whole);
    assert!(o.status.success());
    let again = read_report(&whole);
    assert_eq!(again.summary.resumed, 9);
    assert_eq!(
        again.instances.iter().map(|i| &i.sd).collect::<Vec<_>>(),
        r.instances.iter().map(|i| &i.sd).collect::<Vec<_>>()
    );
    // Another seed draws other weights.
    let other = d.join("other");
    assert!(
        sample(&["--max-sd", "2", "--seed", "6"], &other)
            .status
            .success()
    );
    assert_ne!(read_report(&other).instances[0].sd, r.instances[0].sd);
    // Two shards into their own folders, merged: the same samples as the whole run.
    let parts: Vec<PathBuf> = (0..2).map(|i| d.join(format!("part{i}"))).collect();
    for (i, p) in parts.iter().enumerate() {
        let shard = format!("{i}/2");
        let o = sample(&["--max-sd", "2", "--shard", &shard], p);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    assert_eq!(read_report(&parts[0]).instances.len(), 5);
    let merged = d.join("merged.json");
    let (p0, p1, m) = (
        s(&parts[0].join("instances.json")),
        s(&parts[1].join("instances.json")),
        s(&merged),
    );
    let o = atlasmesh(&["merge-reports", &p0, &p1, "--out", &m]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let merged: atlasmesh::report::InstancesReport =
        serde_json::from_slice(&std::fs::read(&merged).unwrap()).unwrap();
    assert_eq!(merged.summary.written, 9);
    for (a, b) in merged.instances.iter().zip(&r.instances) {
        assert_eq!((&a.name, &a.sd), (&b.name, &b.sd));
    }
    // A shard into a folder holding another shard's report is refused.
    fails(
        &sample(&["--max-sd", "2", "--shard", "1/2"], &parts[0]),
        2,
        &["shard 0/2"],
    );
    // Bad counts and bounds: nothing written.
    let bad = d.join("bad");
    fails(&sample(&["--max-sd", "0.1"], &bad), 2, &["at least 0.5"]);
    assert!(!bad.exists());
}

/// The femur figures: from an atlas of the 30 femurs, 100 samples within 3 σ and the sweeps
/// of modes 1-5 at ±3 σ, as users run them (plots on): every mesh read back from its file is
/// valid and at or above the repair bound, its boundary nodes within 1 % of the element size
/// of the instance's surface read back from its file, in mm.
#[test]
fn femur_samples_and_mode_sweeps_are_valid_fe_models_in_mm() {
    let Some(data) = common::data_dir("femur_samples_and_mode_sweeps_are_valid_fe_models_in_mm")
    else {
        return;
    };
    let d = common::temp_dir("femur-samples");
    let dir = data.join("knee-distal-femur-synthetic-3d/femur");
    let shapes: Vec<String> = (1..=30)
        .map(|k| s(&dir.join(format!("S{k:03}_Femur.ply"))))
        .collect();
    let atlas = s(&d.join("femur.safetensors"));
    let mut args = vec!["build", "--element-size", "2%", "--out", &atlas, "--shapes"];
    args.extend(shapes.iter().map(String::as_str));
    let o = atlasmesh(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let samples = d.join("samples");
    let o = atlasmesh(&[
        "sample",
        "--atlas",
        &atlas,
        "--n",
        "100",
        "--seed",
        "7",
        "--max-sd",
        "3",
        "--out",
        &s(&samples),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut runs = vec![(samples.clone(), 100)];
    for m in 1..=5 {
        let out = d.join(format!("mode{m}"));
        let o = atlasmesh(&[
            "instance",
            "--atlas",
            &atlas,
            "--mode",
            &m.to_string(),
            "--steps",
            "-3:3:6",
            "--out",
            &s(&out),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        runs.push((out, 2));
    }
    let mut vtus = Vec::new();
    let mut worst_node_rms: f64 = 0.0;
    for (out, n) in &runs {
        let r = read_report(out);
        assert_eq!(r.instances.len(), *n, "{}", out.display());
        assert!(r.data_unit);
        assert!(out.join("instances.html").is_file());
        for i in &r.instances {
            assert!(i.mahalanobis <= 3.0 * (r.modes as f64).sqrt() + 1e-9);
            let base = out.join(&i.name);
            let mesh: atlasmesh::mesh::FeMesh<3> =
                atlasmesh::formats::read_fe_mesh(&base.join(format!("{}_mesh.vtu", i.name)))
                    .unwrap();
            let per = atlasmesh::mesh::quality::mesh_quality(&mesh);
            let q = atlasmesh::mesh::quality::summarize(&per);
            assert_eq!(q.inverted_elements, 0, "{}", i.name);
            assert!(
                q.scaled_jacobian_min >= i.repair_bound - 1e-9 && i.repair_bound >= 0.2,
                "{}: scaled Jacobian {} below the repair bound {}",
                i.name,
                q.scaled_jacobian_min,
                i.repair_bound
            );
            let surface =
                atlasmesh::formats::read_surface(&base.join(format!("{}.vtp", i.name))).unwrap();
            // In mm: a distal femur is 60-110 mm across and the elements about 2 mm.
            let diag = surface.bbox_diagonal();
            assert!(
                diag > 60.0 && diag < 200.0,
                "{}: diagonal {diag} mm",
                i.name
            );
            assert!(
                i.element_size > 1.5 && i.element_size < 3.0,
                "{}: {}",
                i.name,
                i.element_size
            );
            let index = atlasmesh::geometry::ClosestPointIndex::from_shape(&surface);
            let nodes = atlasmesh::mesh::boundary_surface(&mesh).points;
            let rms = (nodes.iter().map(|p| index.closest(p).dist2).sum::<f64>()
                / nodes.len() as f64)
                .sqrt();
            assert!(
                rms <= 0.01 * i.element_size,
                "{}: boundary nodes {rms} mm (RMS) off the surface, elements of {} mm",
                i.name,
                i.element_size
            );
            assert!((rms - i.boundary_node_rms_distance).abs() < 1e-6 * i.element_size);
            worst_node_rms = worst_node_rms.max(rms / i.element_size);
            vtus.push(base.join(format!("{}_mesh.vtu", i.name)));
        }
    }
    eprintln!(
        "femur instances: {} meshes valid, boundary nodes at most {:.2} % of the element size off their surface (RMS)",
        vtus.len(),
        100.0 * worst_node_rms
    );
    // A second program reads some of them alike.
    let some: Vec<PathBuf> = vtus.iter().step_by(10).cloned().collect();
    if let Some(meshes) = common::meshio_meshes(&some) {
        for (f, (points, cells)) in some.iter().zip(meshes) {
            let m: atlasmesh::mesh::FeMesh<3> = atlasmesh::formats::read_fe_mesh(f).unwrap();
            assert_eq!(
                (points.len(), cells.len()),
                (m.nodes.len(), m.num_elements())
            );
        }
    }
}

/// `--sets` and `--deck` reach every instance as they reach fitted subjects: the sets in the
/// mesh files, and a deck per instance with its node coordinates (CalculiX reads it in the
/// solver tests).
#[test]
fn instances_carry_the_sets_and_get_their_decks() {
    let d = common::temp_dir("instance-deck");
    let atlas = atlas_2d(&d);
    let sets = d.join("sets.toml");
    std::fs::write(
        &sets,
        "[[node_set]]\nname = \"BASE\"\nhalf_space = { axis = \"longest\", below = 0.1 }\n[[element_set]]\nname = \"TOP\"\nhalf_space = { axis = \"longest\", above = 0.5 }\n",
    )
    .unwrap();
    let mean = d.join("mean.inp");
    let o = atlasmesh(&["convert", &s(&atlas), &s(&mean)]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let deck = d.join("deck.inp");
    let mut text = std::fs::read_to_string(&mean).unwrap();
    text.push_str("*MATERIAL, NAME=M\n*ELASTIC\n1000, 0.3\n");
    std::fs::write(&deck, text).unwrap();
    let out = d.join("out");
    let o = atlasmesh(&[
        "instance",
        "--atlas",
        &s(&atlas),
        "--mode",
        "2",
        "--steps",
        "-2:2:4",
        "--sets",
        &s(&sets),
        "--deck",
        &s(&deck),
        "--format",
        "inp,vtu",
        "--out",
        &s(&out),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for r in &read_report(&out).instances {
        let base = out.join(&r.name);
        let mesh: atlasmesh::mesh::FeMesh<2> =
            atlasmesh::formats::read_fe_mesh(&base.join(format!("{}_mesh.inp", r.name))).unwrap();
        assert!(mesh.sets.node_sets.contains_key("BASE"), "{}", r.name);
        assert!(mesh.sets.element_sets.contains_key("TOP"), "{}", r.name);
        let deck_file = base.join(format!("{}_deck.inp", r.name));
        assert!(r.files.contains(&format!("{0}/{0}_deck.inp", r.name)));
        let deck_text = std::fs::read_to_string(&deck_file).unwrap();
        assert!(deck_text.contains("*MATERIAL, NAME=M"));
        let in_deck: atlasmesh::mesh::FeMesh<2> =
            atlasmesh::formats::read_fe_mesh(&deck_file).unwrap();
        assert_eq!(in_deck.nodes.len(), mesh.nodes.len());
        for (p, q) in in_deck.nodes.iter().zip(&mesh.nodes) {
            assert!((p[0] - q[0]).abs() + (p[1] - q[1]).abs() < 1e-9);
        }
    }
}
