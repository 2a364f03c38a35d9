//! `atlasmesh instance` as users run it: a sweep of the first mode, each instance's surface
//! and FE mesh in the data's unit, every mesh valid and close to its surface, read back by
//! atlasmesh and by meshio (when there is a Python with it).

use crate::bad_input::{atlas_2d, fails, files_in};
use crate::common::{self, atlasmesh};
use std::path::{Path, PathBuf};

fn s(p: &Path) -> String {
    p.display().to_string()
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
    let reports: Vec<atlasmesh::study::InstanceReport> =
        serde_json::from_slice(&std::fs::read(out.join("instances.json")).unwrap()).unwrap();
    assert_eq!(reports.len(), 7);
    // The population's size (the demo outlines are about 2 units across).
    let pop = atlasmesh::study::demo_population(12, 120, 5);
    let size = |pts: &[[f64; 2]]| {
        let (lo, hi) = atlasmesh::geometry::bounding_box(pts);
        (hi[0] - lo[0]).max(hi[1] - lo[1])
    };
    let pop_size = pop.iter().map(|s| size(&s.points)).sum::<f64>() / pop.len() as f64;
    let mut mesh_files: Vec<PathBuf> = Vec::new();
    let mut read: Vec<atlasmesh::mesh::FeMesh<2>> = Vec::new();
    for r in &reports {
        assert_eq!(r.inverted_elements, 0, "{}", r.name);
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
