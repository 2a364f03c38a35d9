//! Solver-ready output, checked by the real programs: CalculiX (`ccx`) solves a
//! linear-elastic step on morphed femur meshes whose node sets came from a sets config on the
//! mean; Gmsh loads every `.msh`; meshio reads back every format; a template `.inp` with sets
//! morphed to three femurs keeps the same set members in every output format.
//!
//! The programs: `ccx` and `gmsh` on the PATH, and a Python with meshio named by
//! `ATLASMESH_PYTHON` (`.ci/run` installs all three and sets `ATLASMESH_REQUIRE_TOOLS=1`, so
//! that a missing one fails there; elsewhere the checks that need them say they were skipped).

use crate::common;

use atlasmesh::mesh::{FeMesh, MeshSets};
use std::path::{Path, PathBuf};
use std::process::Command;

fn atlasmesh(args: &[&str]) {
    let o = common::atlasmesh(args);
    assert!(
        o.status.success(),
        "atlasmesh {args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// The femurs' sets (tests/fixtures/femur_sets.toml, which the Python tests read too).
const SETS: &str = include_str!("../fixtures/femur_sets.toml");

/// The sets of a `.feb` file, read with string matching (no FEBio reader in atlasmesh).
fn feb_sets(path: &Path) -> MeshSets {
    let t = std::fs::read_to_string(path).unwrap();
    let mut s = MeshSets::default();
    let ids = |body: &str| -> Vec<usize> {
        body.split(',')
            .map(|v| v.trim().parse::<usize>().unwrap() - 1)
            .collect()
    };
    for (tag, target) in [("NodeSet", 0), ("ElementSet", 1)] {
        for part in t.split(&format!("<{tag} name=\"")).skip(1) {
            let name = &part[..part.find('"').unwrap()];
            let body = &part[part.find('>').unwrap() + 1..part.find(&format!("</{tag}>")).unwrap()];
            if target == 0 {
                s.node_sets.insert(name.into(), ids(body));
            } else {
                s.element_sets.insert(name.into(), ids(body));
            }
        }
    }
    for part in t.split("<Surface name=\"").skip(1) {
        let name = &part[..part.find('"').unwrap()];
        let n = part[..part.find("</Surface>").unwrap()]
            .matches("<quad4")
            .count();
        s.surfaces.insert(name.into(), vec![(0, 0); n]);
    }
    s
}

#[test]
fn femur_decks_solved_by_calculix_and_formats_read_back() {
    let Some(data) = common::data_dir("femur_decks_solved_by_calculix_and_formats_read_back")
    else {
        return;
    };
    let dir = common::temp_dir("solver-femur");
    let femur = |k: usize| femur_path(&data, k);
    let sets = dir.join("sets.toml");
    std::fs::write(&sets, SETS).unwrap();
    let s = |p: &Path| p.display().to_string();
    // 1. An atlas of S004-S030 with a coarse automatic hex mesh; its mean mesh with the sets.
    let atlas = dir.join("atlas.safetensors");
    let mut args = vec!["build".to_string(), "--shapes".into()];
    args.extend((4..=30).map(femur));
    args.extend(
        [
            "--modes",
            "10",
            "--element-size",
            "4%",
            "--no-plots",
            "--out",
        ]
        .map(String::from),
    );
    args.push(s(&atlas));
    atlasmesh(&args.iter().map(String::as_str).collect::<Vec<_>>());
    let mean = dir.join("mean.inp");
    atlasmesh(&["convert", &s(&atlas), &s(&mean), "--sets", &s(&sets)]);
    let deck = dir.join("deck.inp");
    std::fs::write(
        &deck,
        std::fs::read_to_string(&mean).unwrap() + common::CCX_STEP,
    )
    .unwrap();
    // 2. Three femurs fitted: a deck each, and the mesh in every format.
    let out = dir.join("fit");
    atlasmesh(&[
        "fit",
        "--atlas",
        &s(&atlas),
        "--subject",
        &femur(1),
        &femur(2),
        &femur(3),
        "--deck",
        &s(&deck),
        "--sets",
        &s(&sets),
        "--format",
        "inp,msh,feb,vtu,vtk",
        "--no-plots",
        "--out",
        &s(&out),
    ]);
    let reference: FeMesh<3> = atlasmesh::formats::read_fe_mesh(&mean).unwrap();
    assert_eq!(
        reference.sets.node_sets.keys().collect::<Vec<_>>(),
        ["FIXED", "LOAD"]
    );
    for k in 1..=3 {
        let base = out.join(format!("S{k:03}_Femur"));
        for ext in ["inp", "msh", "vtu", "vtk"] {
            let m: FeMesh<3> =
                atlasmesh::formats::read_fe_mesh(&base.join(format!("S{k:03}_Femur_mesh.{ext}")))
                    .unwrap();
            assert_eq!(m.connectivity, reference.connectivity, "{ext}");
            assert_eq!(m.sets.node_sets, reference.sets.node_sets, "{ext}");
            assert_eq!(m.sets.element_sets, reference.sets.element_sets, "{ext}");
            if ext == "inp" || ext == "msh" {
                assert_eq!(m.sets.surfaces, reference.sets.surfaces, "{ext}");
            }
        }
        let f = feb_sets(&base.join(format!("S{k:03}_Femur_mesh.feb")));
        assert_eq!(f.node_sets, reference.sets.node_sets, "feb");
        assert_eq!(f.element_sets, reference.sets.element_sets, "feb");
        assert_eq!(
            f.surfaces["DISTAL"].len(),
            reference.sets.surfaces["DISTAL"].len()
        );
    }
    // 3. CalculiX solves every subject's deck.
    if common::tool("ccx", "CalculiX solves") {
        for k in 1..=3 {
            let u = common::solve(&out.join(format!("S{k:03}_Femur/S{k:03}_Femur_deck.inp")));
            assert_eq!(u.len(), reference.sets.node_sets["LOAD"].len());
            assert!(u.iter().flatten().all(|v| v.is_finite()));
            let mean_uz = u.iter().map(|v| v[2]).sum::<f64>() / u.len() as f64;
            eprintln!("S{k:03}: ccx solved; mean z displacement of LOAD {mean_uz:.3e} mm");
            assert!(u.iter().any(|v| v.iter().any(|c| *c != 0.0)));
        }
    }
    // 4. Gmsh loads every .msh; meshio reads back every format with the same counts and sets.
    if common::tool("gmsh", "gmsh -check") {
        for k in 1..=3 {
            let p = out.join(format!("S{k:03}_Femur/S{k:03}_Femur_mesh.msh"));
            let o = crate::common::run(
                Command::new("gmsh").arg("-check").arg(&p),
                crate::common::deadline::GMSH,
            );
            let log = String::from_utf8_lossy(&o.stdout).to_string()
                + &String::from_utf8_lossy(&o.stderr);
            assert!(o.status.success() && !log.contains("Error"), "{log}");
            // One point entity per node set, not one per node.
            let text = std::fs::read_to_string(&p).unwrap();
            let points: usize = text
                .split("$Entities\n")
                .nth(1)
                .and_then(|r| r.split_whitespace().next())
                .and_then(|n| n.parse().ok())
                .unwrap();
            let sets = atlasmesh::formats::read_msh(&p)
                .unwrap()
                .sets
                .node_sets
                .len();
            assert_eq!(points, sets, "{}: point entities", p.display());
        }
    }
    if let Some(py) = common::python() {
        meshio_check(
            &py,
            &out.join("S001_Femur/S001_Femur_mesh"),
            &reference,
            "hexahedron",
        );
        // And a quadrilateral mesh (the 2D demo's atlas, its mean mesh with sets).
        let quad_dir = dir.join("quad");
        let demo = crate::common::run(
            Command::new(env!("CARGO_BIN_EXE_atlasmesh"))
                .args(["demo", "--out"])
                .arg(&quad_dir)
                .arg("--quiet"),
            crate::common::deadline::ATLASMESH,
        );
        assert!(demo.status.success());
        let qsets = dir.join("q.toml");
        std::fs::write(
            &qsets,
            "[[node_set]]\nname = \"BASE\"\nhalf_space = { axis = \"y\", below = 0.1 }\n[[element_set]]\nname = \"TOP\"\nhalf_space = { axis = \"y\", above = 0.5 }\n[[surface]]\nname = \"RIM\"\nfacing = { direction = [1, 0], angle = 60 }\n",
        )
        .unwrap();
        let qbase = dir.join("quad_mesh");
        for ext in ["inp", "msh", "vtu", "vtk"] {
            atlasmesh(&[
                "convert",
                &s(&quad_dir.join("atlas.safetensors")),
                &format!("{}.{ext}", s(&qbase)),
                "--sets",
                &s(&qsets),
            ]);
        }
        let q: FeMesh<2> = atlasmesh::formats::read_fe_mesh(&qbase.with_extension("inp")).unwrap();
        let q3 = FeMesh {
            nodes: q.nodes.iter().map(|p| [p[0], p[1], 0.0]).collect(),
            kind: q.kind,
            connectivity: q.connectivity.clone(),
            sets: q.sets.clone(),
        };
        meshio_check(&py, &qbase, &q3, "quad");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// meshio reads `base.{inp,msh,vtu,vtk}` with the node and element counts of `reference` and
/// the same set sizes.
fn meshio_check(py: &Path, base: &Path, reference: &FeMesh<3>, kind: &str) {
    let script = r#"
import sys, json, meshio
base, kind = sys.argv[1], sys.argv[2]
out = {}
for ext in ["inp", "msh", "vtu", "vtk"]:
    m = meshio.read(base + "." + ext)
    cells = sum(len(c.data) for c in m.cells if c.type == kind)
    sets = {}
    if ext == "inp":
        for k, v in m.point_sets.items():
            sets["n:" + k] = len(v)
        for k, v in m.cell_sets.items():
            sets["e:" + k] = sum(len(x) for x in v)
    elif ext == "msh":
        for k, v in m.cell_sets.items():
            if k.startswith("gmsh:"):
                continue
            n = [len(x) if x is not None else 0 for x in v]
            types = [c.type for c in m.cells]
            vert = sum(a for a, t in zip(n, types) if t == "vertex")
            el = sum(a for a, t in zip(n, types) if t == kind)
            face = sum(a for a, t in zip(n, types) if t not in ("vertex", kind))
            if vert: sets["n:" + k] = vert
            if el: sets["e:" + k] = el
            if face: sets["s:" + k] = face
    else:
        for k, v in m.point_data.items():
            if k.startswith("set_"): sets["n:" + k[4:]] = int(v.sum())
        for k, v in m.cell_data.items():
            if k.startswith("set_"): sets["e:" + k[4:]] = int(sum(x.sum() for x in v))
    out[ext] = {"points": len(m.points), "cells": cells, "sets": sets}
print(json.dumps(out))
"#;
    let o = crate::common::run(
        Command::new(py)
            .arg("-c")
            .arg(script)
            .arg(base.display().to_string())
            .arg(kind),
        crate::common::deadline::PYTHON,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let mut expected: Vec<(String, usize)> = Vec::new();
    for (k, m) in &reference.sets.node_sets {
        expected.push((format!("n:{k}"), m.len()));
    }
    for (k, m) in &reference.sets.element_sets {
        expected.push((format!("e:{k}"), m.len()));
    }
    for ext in ["inp", "msh", "vtu", "vtk"] {
        let r = &v[ext];
        assert_eq!(r["points"], reference.nodes.len(), "{ext} points");
        assert_eq!(r["cells"], reference.num_elements(), "{ext} cells");
        for (k, n) in &expected {
            assert_eq!(r["sets"][k], *n, "meshio {ext}: set {k}");
        }
        if ext == "msh" {
            for (k, f) in &reference.sets.surfaces {
                assert_eq!(
                    r["sets"][format!("s:{k}")],
                    f.len(),
                    "meshio msh: surface {k}"
                );
            }
        }
    }
    eprintln!(
        "meshio read back {} in 4 formats with its sets",
        base.display()
    );
}

/// `S{k:03}_Femur.ply` of the femur data under `data`.
fn femur_path(data: &Path, k: usize) -> String {
    data.join(format!(
        "knee-distal-femur-synthetic-3d/femur/S{k:03}_Femur.ply"
    ))
    .display()
    .to_string()
}

/// A template FE mesh in S001's frame: an atlas of S002-S012 with an automatic hex mesh of
/// `element_size`, fitted to S001 with the sets of `sets`, written as `.inp` in `dir`.
fn femur_template(data: &Path, dir: &Path, sets: &Path, element_size: &str) -> PathBuf {
    let s = |p: &Path| p.display().to_string();
    let a0 = dir.join("a0.safetensors");
    let mut args = vec!["build".to_string(), "--shapes".into()];
    args.extend((2..=12).map(|k| femur_path(data, k)));
    args.extend(
        [
            "--modes",
            "8",
            "--element-size",
            element_size,
            "--no-plots",
            "--out",
        ]
        .map(String::from),
    );
    args.push(s(&a0));
    atlasmesh(&args.iter().map(String::as_str).collect::<Vec<_>>());
    let t = dir.join("t");
    atlasmesh(&[
        "fit",
        "--atlas",
        &s(&a0),
        "--subject",
        &femur_path(data, 1),
        "--sets",
        &s(sets),
        "--format",
        "inp",
        "--no-plots",
        "--out",
        &s(&t),
    ]);
    t.join("S001_Femur/S001_Femur_mesh.inp")
}

/// Round trip: a template `.inp` with sets (a femur's morphed mesh) as the atlas's FE mesh,
/// morphed to three femurs; the sets have the same members in every output format.
#[test]
fn template_inp_with_sets_morphed_to_three_femurs() {
    let Some(data) = common::data_dir("template_inp_with_sets_morphed_to_three_femurs") else {
        return;
    };
    let dir = common::temp_dir("solver-template");
    let femur = |k: usize| femur_path(&data, k);
    let s = |p: &Path| p.display().to_string();
    let sets = dir.join("sets.toml");
    std::fs::write(&sets, SETS).unwrap();
    // The template: an automatic mesh morphed to S001, written as .inp with the sets.
    let template = femur_template(&data, &dir, &sets, "5%");
    let tm: FeMesh<3> = atlasmesh::formats::read_fe_mesh(&template).unwrap();
    assert!(!tm.sets.node_sets.is_empty() && !tm.sets.surfaces.is_empty());
    // The atlas with that template mesh (S001 first), then three other femurs.
    let a1 = dir.join("a1.safetensors");
    let mut args = vec!["build".to_string(), "--shapes".into(), femur(1)];
    args.extend((13..=25).map(femur));
    args.extend(["--template-mesh".to_string(), s(&template)]);
    args.extend(["--modes", "8", "--no-plots", "--out"].map(String::from));
    args.push(s(&a1));
    atlasmesh(&args.iter().map(String::as_str).collect::<Vec<_>>());
    let out = dir.join("out");
    atlasmesh(&[
        "fit",
        "--atlas",
        &s(&a1),
        "--subject",
        &femur(26),
        &femur(27),
        &femur(28),
        "--format",
        "inp,msh,feb,vtu",
        "--no-plots",
        "--out",
        &s(&out),
    ]);
    for k in 26..=28 {
        for ext in ["inp", "msh", "vtu"] {
            let m: FeMesh<3> = atlasmesh::formats::read_fe_mesh(
                &out.join(format!("S{k:03}_Femur/S{k:03}_Femur_mesh.{ext}")),
            )
            .unwrap();
            assert_eq!(m.connectivity, tm.connectivity, "{ext}");
            assert_eq!(m.sets.node_sets, tm.sets.node_sets, "S{k:03} {ext}");
            assert_eq!(m.sets.element_sets, tm.sets.element_sets, "S{k:03} {ext}");
            if ext != "vtu" {
                assert_eq!(m.sets.surfaces, tm.sets.surfaces, "S{k:03} {ext}");
            }
        }
        let f = feb_sets(&out.join(format!("S{k:03}_Femur/S{k:03}_Femur_mesh.feb")));
        assert_eq!(f.node_sets, tm.sets.node_sets);
        assert_eq!(f.element_sets, tm.sets.element_sets);
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Quadratic elements (issue 5): a template mesh made quadratic (`convert --quadratic`, hex8
/// to hex20; its node sets gain the mid-edge nodes) and a 10-node tetrahedral mesh made by
/// Gmsh (`-order 2`) serve as an atlas's FE mesh; morphed to femurs, written in every format
/// with the mid-edge nodes in each program's order, read back by atlasmesh, meshio and Gmsh,
/// and solved by CalculiX (C3D20, C3D10).
#[test]
fn quadratic_hex20_and_tet10_meshes_morphed_and_solved() {
    let Some(data) = common::data_dir("quadratic_hex20_and_tet10_meshes_morphed_and_solved") else {
        return;
    };
    let dir = common::temp_dir("solver-quadratic");
    let femur = |k: usize| femur_path(&data, k);
    let s = |p: &Path| p.display().to_string();
    let sets = dir.join("sets.toml");
    std::fs::write(&sets, SETS).unwrap();
    // Hex20: a coarse hex mesh morphed to S001 (with the sets), made quadratic.
    let template = femur_template(&data, &dir, &sets, "6%");
    let linear: FeMesh<3> = atlasmesh::formats::read_fe_mesh(&template).unwrap();
    let t20 = dir.join("t20.inp");
    atlasmesh(&["convert", &s(&template), &s(&t20), "--quadratic"]);
    let hex20: FeMesh<3> = atlasmesh::formats::read_fe_mesh(&t20).unwrap();
    assert_eq!(hex20.kind, atlasmesh::mesh::ElementKind::Hex20);
    assert_eq!(hex20.num_elements(), linear.num_elements());
    assert_eq!(hex20.connectivity[..20][..8], linear.connectivity[..8]);
    // A node set gains the mid-edge nodes between its members.
    assert!(hex20.sets.node_sets["LOAD"].len() > linear.sets.node_sets["LOAD"].len());
    assert_eq!(hex20.sets.element_sets, linear.sets.element_sets);
    assert_eq!(hex20.sets.surfaces, linear.sets.surfaces);
    // Tet10: Gmsh remeshes S001's surface at about 10 mm and fills it with 10-node
    // tetrahedra (mid-edge nodes on straight edges: its curved placement on the reclassified
    // surface can fail).
    let tet10 = if common::tool("gmsh", "a tet10 mesh made by Gmsh") {
        let full = atlasmesh::formats::read_surface(Path::new(&femur(1))).unwrap();
        atlasmesh::formats::write_stl(&dir.join("s1.stl"), &full).unwrap();
        std::fs::write(
            dir.join("t10.geo"),
            "Merge \"s1.stl\";\nClassifySurfaces{40 * Pi / 180, 1, 1, Pi};\nCreateGeometry;\nSurface Loop(1) = Surface{:};\nVolume(1) = {1};\nPhysical Volume(\"SOLID\") = {1};\nMesh.MeshSizeMax = 10;\nMesh.ElementOrder = 2;\nMesh.SecondOrderLinear = 1;\n",
        )
        .unwrap();
        let o = crate::common::run(
            Command::new("gmsh")
                .args(["-3", "-format", "msh41", "t10.geo", "-o", "t10.msh"])
                .current_dir(&dir),
            crate::common::deadline::GMSH,
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stdout));
        let m: FeMesh<3> = atlasmesh::formats::read_fe_mesh(&dir.join("t10.msh")).unwrap();
        assert_eq!(m.kind, atlasmesh::mesh::ElementKind::Tet10);
        let q = atlasmesh::mesh::quality::summarize(&atlasmesh::mesh::quality::mesh_quality(&m));
        assert_eq!(
            q.inverted_elements, 0,
            "Gmsh's tet10 mesh read in Gmsh's node order"
        );
        Some(dir.join("t10.msh"))
    } else {
        None
    };
    let mut templates = vec![("hex20", t20.clone(), "hexahedron20")];
    templates.extend(tet10.map(|p| ("tet10", p, "tetra10")));
    for (name, template, meshio_kind) in templates {
        // The atlas with that template mesh (S001 first); its mean mesh with the sets and a
        // deck around it; two femurs fitted, every format written.
        let atlas = dir.join(format!("{name}.safetensors"));
        let mut args = vec!["build".to_string(), "--shapes".into(), femur(1)];
        args.extend((13..=25).map(femur));
        args.extend(["--template-mesh".to_string(), s(&template)]);
        args.extend(["--modes", "8", "--no-plots", "--out"].map(String::from));
        args.push(s(&atlas));
        atlasmesh(&args.iter().map(String::as_str).collect::<Vec<_>>());
        let mean = dir.join(format!("{name}_mean.inp"));
        atlasmesh(&["convert", &s(&atlas), &s(&mean), "--sets", &s(&sets)]);
        let reference: FeMesh<3> = atlasmesh::formats::read_fe_mesh(&mean).unwrap();
        assert_eq!(reference.kind.name(), name);
        let deck = dir.join(format!("{name}_deck.inp"));
        std::fs::write(
            &deck,
            std::fs::read_to_string(&mean).unwrap() + common::CCX_STEP,
        )
        .unwrap();
        let out = dir.join(format!("{name}_out"));
        atlasmesh(&[
            "fit",
            "--atlas",
            &s(&atlas),
            "--subject",
            &femur(26),
            &femur(27),
            "--deck",
            &s(&deck),
            "--sets",
            &s(&sets),
            "--format",
            "inp,msh,feb,vtu,vtk",
            "--no-plots",
            "--out",
            &s(&out),
        ]);
        for k in [26, 27] {
            let base = out.join(format!("S{k:03}_Femur"));
            for ext in ["inp", "msh", "vtu", "vtk"] {
                let m: FeMesh<3> = atlasmesh::formats::read_fe_mesh(
                    &base.join(format!("S{k:03}_Femur_mesh.{ext}")),
                )
                .unwrap();
                assert_eq!(m.kind, reference.kind, "{name} {ext}");
                assert_eq!(m.connectivity, reference.connectivity, "{name} {ext}");
                assert_eq!(m.sets.node_sets, reference.sets.node_sets, "{name} {ext}");
                let q = atlasmesh::mesh::quality::summarize(
                    &atlasmesh::mesh::quality::mesh_quality(&m),
                );
                assert_eq!(q.inverted_elements, 0, "{name} S{k:03}: morphed mesh valid");
            }
            if common::tool("ccx", "CalculiX solves") {
                let u = common::solve(&base.join(format!("S{k:03}_Femur_deck.inp")));
                assert_eq!(u.len(), reference.sets.node_sets["LOAD"].len());
                assert!(u.iter().flatten().all(|v| v.is_finite()));
                assert!(u.iter().any(|v| v.iter().any(|c| *c != 0.0)));
                let mean_uz = u.iter().map(|v| v[2]).sum::<f64>() / u.len() as f64;
                eprintln!(
                    "{name} S{k:03}: {} elements, ccx solved; mean z displacement of LOAD {mean_uz:.3e} mm",
                    reference.num_elements()
                );
            }
            if common::tool("gmsh", "gmsh -check") {
                let p = base.join(format!("S{k:03}_Femur_mesh.msh"));
                let o = crate::common::run(
                    Command::new("gmsh").arg("-check").arg(&p),
                    crate::common::deadline::GMSH,
                );
                let log = String::from_utf8_lossy(&o.stdout).to_string()
                    + &String::from_utf8_lossy(&o.stderr);
                assert!(o.status.success() && !log.contains("Error"), "{log}");
            }
        }
        if let Some(py) = common::python() {
            let base = out.join("S026_Femur/S026_Femur_mesh");
            meshio_check(&py, &base, &reference, meshio_kind);
            // The same elements in every format (in any order: the .msh groups them by set):
            // meshio reorders Gmsh's mid-edge nodes to VTK's, as atlasmesh does.
            let script = format!(
                "import meshio, numpy as np\nb = {:?}\nc = [np.concatenate([x.data for x in meshio.read(b + '.' + e).cells if x.type == {meshio_kind:?}]) for e in ['vtu', 'msh', 'inp', 'vtk']]\nr = [sorted(map(tuple, x.tolist())) for x in c]\nprint(all(r[0] == x for x in r[1:]))",
                s(&base)
            );
            let o = crate::common::run(
                Command::new(&py).arg("-c").arg(script),
                crate::common::deadline::PYTHON,
            );
            assert_eq!(
                String::from_utf8_lossy(&o.stdout).trim(),
                "True",
                "{name}: {}",
                String::from_utf8_lossy(&o.stderr)
            );
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// `HexMesh::block(n)` stretched to span `lo`..`hi` (mm), its elements the set `name`.
fn block(lo: [f64; 3], hi: [f64; 3], n: usize, name: &str) -> FeMesh<3> {
    let mut m = atlasmesh::mesh::HexMesh::block(n);
    for p in &mut m.nodes {
        for d in 0..3 {
            p[d] = lo[d] + (hi[d] - lo[d]) * p[d] / n as f64;
        }
    }
    m.sets
        .element_sets
        .insert(name.into(), (0..m.num_elements()).collect());
    m
}

/// A pad of `n` hexahedra per axis (10 × 10 × 2 mm) joined to a bone block of 1 mm ones (10
/// mm cube) by a tie, and the load case that compresses the pad's top 0.1 mm with the bone's
/// bottom held.
fn tied_case(n: usize) -> (FeMesh<3>, atlasmesh::mesh::AppliedLoadCase) {
    let bone = block([0.0; 3], [10.0; 3], 10, "CORE");
    let pad = block([0.0, 0.0, 10.0], [10.0, 10.0, 12.0], n, "PADS");
    let joined = atlasmesh::mesh::join_tied(&bone, "BONE", &pad, 0.01).unwrap();
    // The pad's lower face, nothing else within 0.01 mm of the bone.
    assert_eq!(joined.tied_nodes, (n + 1) * (n + 1));
    let case = atlasmesh::mesh::LoadCase::parse(
        Path::new("case.toml"),
        r#"
[[nodes]]
name = "TOP"
part = "PADS"
face = [0.0, 0.0, 1.0]
[[nodes]]
name = "BOTTOM"
part = "BONE"
face = [0.0, 0.0, -1.0]
[[displacement]]
nodes = "TOP"
z = -0.1
[[displacement]]
nodes = "BOTTOM"
z = 0.0
[[tie]]
nodes = "BONE_TIED"
surface = "BONE_SURFACE"
tolerance = 0.01
"#,
    )
    .unwrap();
    let applied = case.apply(&joined.mesh).unwrap();
    assert_eq!(
        applied.ties,
        vec![("BONE_TIED".into(), "BONE_SURFACE".into(), 0.01)]
    );
    // The tied side as faces: the pad's lower face, n × n quadrilaterals.
    assert_eq!(applied.tie_faces.len(), 1);
    assert_eq!(applied.tie_faces[0].len(), n * n);
    (joined.mesh, applied)
}

/// [`tied_case`] solved by CalculiX: its stiffness (N/mm), bone 1000 MPa, pad 2500 MPa, ν = 0.
fn tied_stiffness(dir: &Path, n: usize) -> f64 {
    let (mesh, applied) = tied_case(n);
    let deck = dir.join(format!("tied_{n}.inp"));
    let quality = atlasmesh::mesh::mesh_quality(&mesh);
    atlasmesh::formats::write_mesh(&deck, &mesh, None, &quality).unwrap();
    let mut text = std::fs::read_to_string(&deck).unwrap();
    text.push_str(
        "*MATERIAL, NAME=BONEM\n*ELASTIC\n1000., 0.\n*SOLID SECTION, ELSET=BONE, MATERIAL=BONEM\n\
         *MATERIAL, NAME=PADM\n*ELASTIC\n2500., 0.\n*SOLID SECTION, ELSET=PADS, MATERIAL=PADM\n",
    );
    atlasmesh::formats::inp_step(&mut text, &applied);
    assert!(text.contains("*TIE, NAME=TIE_1") && text.contains("TYPE=NODE"));
    std::fs::write(&deck, text).unwrap();
    let r = atlasmesh::study::solve_calculix(&deck, &applied, 1).unwrap();
    assert_eq!(r.untied_nodes, 0);
    r.stiffness_n_per_mm
}

/// The FEBio file of a tied load case as febio-python (node sets, load curves) and an XML
/// parser (the conditions: febio-python 0.2.1 fails on a `prescribed displacement`) read it: the held
/// and the displaced sets with their components and values, the ramp, the tie's side
/// (faces whose every node is tied, on the bone's top) paired with the bone's surface in a
/// tied contact, the reaction forces of every displacement set in the log.
const FEB_STEP: &str = r#"
import sys, json, numpy as np, xml.etree.ElementTree as ET
from febio_python.feb import Feb
path = sys.argv[1]
feb = Feb(filepath=path)
names = sorted(s.name for s in feb.get_nodesets())
curves = feb.get_loadcurves()
root = ET.parse(path).getroot()
sets = {s.get("name"): set(int(i) for i in s.text.split(",")) for s in root.iter("NodeSet")}
assert names == sorted(sets), (names, sorted(sets))
bcs = list(root.iter("bc"))
zero = [b for b in bcs if b.get("type") == "zero displacement"]
other = [b for b in bcs if b.get("type") == "prescribed displacement"]
assert len(zero) + len(other) == len(bcs)
nodes = {int(n.get("id")): [float(x) for x in n.text.split(",")] for n in root.iter("node")}
pair = root.find("Mesh/SurfacePair")
contact = root.find("Contact/contact")
side = root.find("Mesh/Surface[@name='TIE_1_NODES']")
faces = [[int(i) for i in f.text.split(",")] for f in side]
tied = set(i for f in faces for i in f)
print(json.dumps({
  "zero": sorted([b.get("node_set")] + [b.findtext(a) for a in ["x_dof", "y_dof", "z_dof"]] for b in zero),
  "prescribed": [[b.get("node_set"), b.findtext("dof"), float(b.findtext("value"))] for b in other],
  "curve": np.asarray(curves[0].data).tolist(),
  "pair": [pair.findtext("primary"), pair.findtext("secondary")],
  "contact": [contact.get("type"), float(contact.findtext("max_distance")), float(contact.findtext("penalty"))],
  "faces": len(faces),
  "tied_in_set": tied <= sets["BONE_TIED"],
  "tied_z": sorted(set(round(nodes[i][2], 9) for i in tied)),
  "logged": sorted(n.get("name") for n in root.iter("node_data")),
  "sets": sorted(sets),
  "analysis": root.findtext("Control/analysis"),
}))
"#;

#[test]
fn a_tied_load_case_written_for_febio_reads_back() {
    let Some(py) = common::python() else {
        return;
    };
    let dir = common::temp_dir("tie-feb");
    let (mesh, applied) = tied_case(7);
    let path = dir.join("tied.feb");
    let quality = atlasmesh::mesh::mesh_quality(&mesh);
    atlasmesh::formats::write_model(&path, &mesh, None, &quality, None, Some(&applied)).unwrap();
    let o = common::run(
        Command::new(&py).arg("-c").arg(FEB_STEP).arg(&path),
        std::time::Duration::from_secs(120),
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    eprintln!("{r}");
    let zero = r["zero"].as_array().unwrap();
    assert!(
        zero.contains(&serde_json::json!(["BOTTOM", "0", "0", "1"])),
        "{zero:?}"
    );
    // The rigid-body holds: x and y held somewhere, z only at BOTTOM.
    assert!(zero.iter().any(|z| z[1] == "1") && zero.iter().any(|z| z[2] == "1"));
    assert_eq!(r["prescribed"], serde_json::json!([["TOP", "z", -0.1]]));
    assert_eq!(r["curve"], serde_json::json!([[0.0, 0.0], [1.0, 1.0]]));
    assert_eq!(
        r["pair"],
        serde_json::json!(["TIE_1_NODES", "BONE_SURFACE"])
    );
    assert_eq!(r["contact"][0], "tied-node-on-facet");
    assert_eq!(r["contact"][1], 0.01);
    assert!(r["contact"][2].as_f64().unwrap() > 0.0);
    assert_eq!(r["faces"], 49);
    assert_eq!(r["tied_in_set"], true);
    assert_eq!(r["tied_z"], serde_json::json!([10.0]));
    let logged: Vec<String> = applied
        .reaction_sets
        .iter()
        .map(|s| format!("RF_{s}"))
        .collect();
    let mut logged = logged;
    logged.sort();
    assert_eq!(r["logged"], serde_json::json!(logged));
    for s in ["TOP", "BOTTOM", "BONE_TIED"] {
        assert!(r["sets"].as_array().unwrap().iter().any(|x| x == s), "{s}");
    }
    assert_eq!(r["analysis"], "STATIC");
}

/// A pad tied to a bone (`join_tied`, the load case's `[[tie]]`, CalculiX's `*TIE`) carries
/// the load of two springs in series (a uniaxial stress, ν = 0): exactly where the meshes'
/// nodes meet, within 1 % where they do not (a node-to-surface tie passes the patch test only
/// approximately: the pad's nodal forces reach the bone through its faces' interpolation).
#[test]
fn a_pad_tied_to_a_bone_carries_the_load_in_series() {
    if !common::tool("ccx", "tied meshes solved by CalculiX") {
        return;
    }
    let dir = common::temp_dir("tie");
    // 100 mm² through 10 mm of 1000 MPa and 2 mm of 2500 MPa.
    let series = 100.0 / (10.0 / 1000.0 + 2.0 / 2500.0);
    let matching = tied_stiffness(&dir, 10);
    assert!(
        (matching / series - 1.0).abs() < 1e-6,
        "{matching} N/mm against {series} N/mm"
    );
    let other = tied_stiffness(&dir, 7);
    assert!(
        (other / series - 1.0).abs() < 0.01,
        "{other} N/mm against {series} N/mm"
    );
}
