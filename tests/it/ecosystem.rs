//! Files as the field's programs save them at their defaults (PyVista/VTK, meshio, Gmsh;
//! `tests/ecosystem/write_files.py`), read by atlasmesh: the geometry equals what the writer
//! was given, and what is refused says why.

use crate::common::{python, temp_dir, tool};
use std::path::Path;

#[derive(serde::Deserialize)]
struct Written {
    file: String,
    kind: String,
    points: Vec<Vec<f64>>,
    cells: Vec<Vec<usize>>,
    refuse: Option<String>,
}

/// Point lists equal to `tol` of the largest coordinate.
fn assert_points(file: &str, got: &[Vec<f64>], want: &[Vec<f64>], tol: f64) {
    assert_eq!(got.len(), want.len(), "{file}: point count");
    let scale = want
        .iter()
        .flatten()
        .fold(0.0f64, |m, v| m.max(v.abs()))
        .max(1.0);
    for (i, (g, w)) in got.iter().zip(want).enumerate() {
        for (a, b) in g.iter().zip(w) {
            assert!(
                (a - b).abs() <= tol * scale,
                "{file}: point {i} is {g:?}, written {w:?}"
            );
        }
    }
}

/// Cells equal as sets of sorted node lists (a reader may orient faces, not change them).
fn assert_cells(file: &str, got: &[Vec<usize>], want: &[Vec<usize>]) {
    let key = |c: &[Vec<usize>]| {
        let mut v: Vec<Vec<usize>> = c
            .iter()
            .map(|c| {
                let mut c = c.clone();
                c.sort_unstable();
                c
            })
            .collect();
        v.sort();
        v
    };
    assert_eq!(key(got), key(want), "{file}: cells");
}

#[test]
fn files_saved_by_pyvista_vtk_meshio_and_gmsh_read_as_written() {
    let Some(py) = python() else { return };
    if !tool("gmsh", "files written by Gmsh") {
        return;
    }
    let dir = temp_dir("ecosystem");
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/ecosystem/write_files.py");
    let o = crate::common::run(
        std::process::Command::new(&py).arg(&script).arg(&dir),
        crate::common::deadline::PYTHON,
    );
    assert!(
        o.status.success(),
        "the writers ran: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let manifest: Vec<Written> =
        serde_json::from_slice(&std::fs::read(dir.join("manifest.json")).unwrap()).unwrap();
    assert!(manifest.len() >= 35, "{} files", manifest.len());
    for w in &manifest {
        let path = dir.join(&w.file);
        // float32 where the writer stores single precision (STL), VTK's legacy ASCII
        // writer's 11 significant digits; else float64.
        let tol = if w.file.ends_with(".stl") {
            1e-6
        } else if w.file.ends_with("_ascii.vtk") {
            1e-9
        } else {
            1e-12
        };
        if let Some(why) = &w.refuse {
            let e = match w.kind.as_str() {
                "surface" => atlasmesh::formats::read_surface(&path).map(|_| ()),
                _ => atlasmesh::formats::read_fe_mesh_raw(&path).map(|_| ()),
            }
            .expect_err(&w.file)
            .to_string();
            assert!(
                e.contains(&w.file) && e.to_lowercase().contains(&why.to_lowercase()),
                "{}: refused saying why: {e}",
                w.file
            );
            continue;
        }
        match w.kind.as_str() {
            "surface" | "surface_area" => {
                assert!(
                    atlasmesh::study::is_surface_file(&path).unwrap(),
                    "{} is a surface",
                    w.file
                );
                let s = atlasmesh::formats::read_surface(&path)
                    .unwrap_or_else(|e| panic!("{}: {e}", w.file));
                let mut got: Vec<Vec<f64>> = s.points.iter().map(|p| p.to_vec()).collect();
                let facets: Vec<Vec<usize>> = s.facets.iter().map(|f| f.to_vec()).collect();
                if w.file.ends_with(".stl") {
                    // STL stores triangles, not shared vertices: welded, in another order.
                    let mut want = w.points.clone();
                    let order = |a: &Vec<f64>, b: &Vec<f64>| a.partial_cmp(b).unwrap();
                    want.sort_by(order);
                    got.sort_by(order);
                    assert_points(&w.file, &got, &want, tol);
                    assert_eq!(facets.len(), w.cells.len(), "{}", w.file);
                    continue;
                }
                assert_points(&w.file, &got, &w.points, tol);
                if w.kind == "surface" {
                    assert_cells(&w.file, &facets, &w.cells);
                } else {
                    // Strips: other triangles, the same surface (its area).
                    let area = |f: &[Vec<usize>]| -> f64 {
                        f.iter()
                            .map(|t| {
                                let p = |i: usize| w.points[t[i]].clone();
                                let (a, b, c) = (p(0), p(1), p(2));
                                let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
                                let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
                                let n = [
                                    u[1] * v[2] - u[2] * v[1],
                                    u[2] * v[0] - u[0] * v[2],
                                    u[0] * v[1] - u[1] * v[0],
                                ];
                                0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt()
                            })
                            .sum()
                    };
                    let (a, b) = (area(&facets), area(&w.cells));
                    assert!((a - b).abs() < 1e-9 * b, "{}: area {a} vs {b}", w.file);
                }
            }
            "outline" => {
                assert!(!atlasmesh::study::is_surface_file(&path).unwrap());
                let s = atlasmesh::formats::read_outlines(&path, true)
                    .unwrap_or_else(|e| panic!("{}: {e}", w.file));
                assert_eq!(s.len(), 1);
                assert!(s[0].is_closed(), "{}: closed", w.file);
                let got: Vec<Vec<f64>> = s[0].points.iter().map(|p| p.to_vec()).collect();
                assert_points(&w.file, &got, &w.points, tol);
            }
            _ => {
                let m = atlasmesh::formats::read_fe_mesh_raw(&path)
                    .unwrap_or_else(|e| panic!("{}: {e}", w.file));
                let got: Vec<Vec<f64>> = m.nodes.iter().map(|p| p.to_vec()).collect();
                assert_points(&w.file, &got, &w.points, tol);
                let cells: Vec<Vec<usize>> = (0..m.num_elements())
                    .map(|e| m.element(e).to_vec())
                    .collect();
                if w.kind == "gmsh" {
                    // Gmsh's own files: the same tetrahedra as meshio reads, and the
                    // physical groups as sets.
                    assert_cells(&w.file, &cells, &w.cells);
                    assert!(
                        m.sets.element_sets.contains_key("bone"),
                        "{}: {:?}",
                        w.file,
                        m.sets.element_sets.keys()
                    );
                    assert!(m.sets.surfaces.contains_key("base"), "{}", w.file);
                } else {
                    assert_eq!(cells, w.cells, "{}: cells in order", w.file);
                }
            }
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A femur saved by PyVista at its defaults (binary, zlib-compressed VTP) is fitted exactly
/// as the same femur in the data's PLY: the same mesh, node for node. The fit also writes an
/// FEBio model around the mean mesh (`--deck model.feb`), read back by febio-python with the
/// subject's nodes and the model's material; its mesh in every format and its fitted surface
/// as VTP, VTK, PLY and STL, read back by meshio, VTK (PyVista) and atlasmesh.
#[test]
fn a_femur_saved_by_pyvista_fits_as_its_ply() {
    let Some(data) = crate::common::data_dir("a_femur_saved_by_pyvista_fits_as_its_ply") else {
        return;
    };
    let Some(py) = python() else { return };
    let femurs = data.join("knee-distal-femur-synthetic-3d/femur");
    let ply = |k: usize| femurs.join(format!("S{k:03}_Femur.ply"));
    let dir = temp_dir("pyvista-femur");
    let atlas = dir.join("atlas.safetensors");
    let mut args: Vec<String> = vec!["build".into(), "--shapes".into()];
    args.extend((2..=16).map(|k| ply(k).display().to_string()));
    args.extend(["--modes", "5", "--out", &atlas.display().to_string()].map(String::from));
    let o = crate::common::atlasmesh(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let subjects = dir.join("subjects");
    std::fs::create_dir_all(&subjects).unwrap();
    std::fs::copy(ply(1), subjects.join("S001_Femur.ply")).unwrap();
    let vtp = subjects.join("S001_pyvista.vtp");
    let o = crate::common::run(
        std::process::Command::new(&py)
            .args([
                "-c",
                "import sys, pyvista; pyvista.read(sys.argv[1]).save(sys.argv[2])",
            ])
            .arg(ply(1))
            .arg(&vtp),
        crate::common::deadline::PYTHON,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let head = std::fs::read(&vtp).unwrap();
    assert!(
        String::from_utf8_lossy(&head[..400.min(head.len())]).contains("vtkZLibDataCompressor"),
        "PyVista's default VTP is compressed"
    );
    // An FEBio model around the mean mesh: its .feb with a material, a domain and a step.
    let mean = dir.join("mean.feb");
    let o = crate::common::atlasmesh(&[
        "convert",
        &atlas.display().to_string(),
        &mean.display().to_string(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let model = std::fs::read_to_string(&mean).unwrap().replace(
        "  <Mesh>",
        "  <Module type=\"solid\"/>\n  <Material>\n    <material id=\"1\" name=\"bone\" type=\"isotropic elastic\"><E>17000</E><v>0.3</v></material>\n  </Material>\n  <Mesh>",
    ).replace(
        "  </Mesh>",
        "  </Mesh>\n  <MeshDomains>\n    <SolidDomain name=\"Part1\" mat=\"bone\"/>\n  </MeshDomains>\n  <Step>\n    <step id=\"1\" name=\"load\"><Control><analysis>STATIC</analysis></Control></step>\n  </Step>",
    );
    let deck = dir.join("model.feb");
    std::fs::write(&deck, model).unwrap();
    let out = dir.join("fit");
    let o = crate::common::atlasmesh(&[
        "fit",
        "--atlas",
        &atlas.display().to_string(),
        "--subjects",
        &subjects.display().to_string(),
        "--deck",
        &deck.display().to_string(),
        "--format",
        "vtu,vtk,msh,inp,feb",
        "--surface-format",
        "vtp,vtk,ply,stl",
        "--out",
        &out.display().to_string(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let base = out.join("S001_pyvista/S001_pyvista");
    let check = r#"
import sys, meshio, numpy as np
from febio_python.feb import Feb
base = sys.argv[1]
mesh = meshio.read(base + "_mesh.vtu")
feb = Feb(filepath=base + "_deck.feb")
nodes = np.concatenate([n.coordinates for n in feb.get_nodes(dtype=np.float64)])
assert nodes.shape == mesh.points.shape, (nodes.shape, mesh.points.shape)
assert np.abs(nodes - mesh.points).max() < 1e-9 * np.abs(mesh.points).max(), "deck nodes"
els = feb.get_elements()
assert els[0].type == "hex8", els[0].type
assert (np.asarray(els[0].connectivity) == mesh.cells[0].data).all(), "deck elements"
assert [m.name for m in feb.get_materials()] == ["bone"]
assert [d.mat for d in feb.get_mesh_domains()] == ["bone"]
fit = meshio.read(base + "_fit.vtk")
for ext in ["ply", "stl"]:
    s = meshio.read(base + "_fit." + ext)
    assert len(s.cells[0].data) == len(fit.cells[0].data), ext
    assert np.abs(np.sort(s.points, 0) - np.sort(fit.points, 0)).max() < 1e-4 * np.abs(fit.points).max(), ext
# VTK (through PyVista's readers) reads every mesh and surface file VTK has a reader for.
import pyvista
for ext in ["vtu", "vtk"]:
    g = pyvista.read(base + "_mesh." + ext)
    assert g.n_points == len(mesh.points) and g.n_cells == len(mesh.cells[0].data), ext
    assert np.abs(np.asarray(g.points) - mesh.points).max() < 1e-9 * np.abs(mesh.points).max(), ext
for ext in ["vtp", "vtk", "ply", "stl"]:
    s = pyvista.read(base + "_fit." + ext)
    assert s.n_cells == len(fit.cells[0].data), (ext, s.n_cells)
print(len(nodes), "nodes,", len(fit.cells[0].data), "triangles")
"#;
    let o = crate::common::run(
        std::process::Command::new(&py)
            .args(["-c", check])
            .arg(&base),
        crate::common::deadline::PYTHON,
    );
    assert!(
        o.status.success(),
        "febio-python and meshio read the deck and surfaces: {}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    let vtp = atlasmesh::formats::read_vtp(&base.with_file_name("S001_pyvista_fit.vtp")).unwrap();
    for ext in ["ply", "vtk"] {
        let s = atlasmesh::formats::read_surface(
            &base.with_file_name(format!("S001_pyvista_fit.{ext}")),
        )
        .unwrap();
        assert_eq!(s.points.len(), vtp.points.len(), "{ext}");
    }
    let mesh = |name: &str| {
        atlasmesh::formats::read_vtu(&out.join(name).join(format!("{name}_mesh.vtu"))).unwrap()
    };
    let (a, b) = (mesh("S001_Femur"), mesh("S001_pyvista"));
    assert_eq!(a.connectivity, b.connectivity);
    let worst = a
        .nodes
        .iter()
        .zip(&b.nodes)
        .map(|(p, q)| (0..3).map(|i| (p[i] - q[i]).abs()).fold(0.0, f64::max))
        .fold(0.0, f64::max);
    assert!(worst <= 1e-9, "the two meshes differ by {worst} mm");
    std::fs::remove_dir_all(&dir).ok();
}
