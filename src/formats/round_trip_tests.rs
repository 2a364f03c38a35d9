use super::abaqus::inp;
use super::*;
use crate::geometry::Point;
use crate::mesh::{ElementKind, FeMesh, MeshSets};

fn two_cubes() -> FeMesh<3> {
    let mut nodes = Vec::new();
    for z in 0..2 {
        for y in 0..2 {
            for x in 0..3 {
                nodes.push([x as f64 * 1.5, y as f64, z as f64 + 0.25]);
            }
        }
    }
    let id = |x: usize, y: usize, z: usize| x + 3 * y + 6 * z;
    let hex = |x: usize| {
        vec![
            id(x, 0, 0),
            id(x + 1, 0, 0),
            id(x + 1, 1, 0),
            id(x, 1, 0),
            id(x, 0, 1),
            id(x + 1, 0, 1),
            id(x + 1, 1, 1),
            id(x, 1, 1),
        ]
    };
    let mut sets = MeshSets::default();
    sets.node_sets.insert("LEFT".into(), vec![0, 3, 6, 9]);
    sets.node_sets.insert("ONE".into(), vec![5]);
    sets.element_sets.insert("RIGHT".into(), vec![1]);
    sets.surfaces.insert("END".into(), vec![(1, 3)]);
    sets.surfaces.insert("BOTTOM".into(), vec![(0, 0), (1, 0)]);
    FeMesh {
        nodes,
        kind: ElementKind::Hex8,
        connectivity: [hex(0), hex(1)].concat(),
        sets,
    }
}

fn quads() -> FeMesh<2> {
    let nodes = vec![
        [0.0, 0.0],
        [1.0, 0.0],
        [2.0, 0.0],
        [0.0, 1.0],
        [1.0, 1.0],
        [2.0, 1.0],
    ];
    let mut sets = MeshSets::default();
    sets.node_sets.insert("BASE".into(), vec![0, 1, 2]);
    sets.element_sets.insert("FIRST".into(), vec![0]);
    sets.surfaces.insert("TOP".into(), vec![(0, 2), (1, 2)]);
    FeMesh {
        nodes,
        kind: ElementKind::Quad4,
        connectivity: vec![0, 1, 4, 3, 1, 2, 5, 4],
        sets,
    }
}

fn round_trip<const D: usize>(m: &FeMesh<D>, name: &str) {
    let tmp = tempfile::Builder::new()
        .prefix("atlasmesh-rt-")
        .tempdir()
        .unwrap();
    let dir = tmp.path();
    let q = crate::mesh::quality::mesh_quality(m);
    for ext in ["inp", "msh", "vtk", "vtu"] {
        let p = dir.join(format!("{name}.{ext}"));
        write_mesh(&p, m, None, &q).unwrap();
        let r: FeMesh<D> = crate::formats::read_fe_mesh(&p).unwrap();
        // .inp keeps 13 significant digits (CalculiX reads 20 characters per number).
        let tol = if ext == "inp" { 1e-11 } else { 1e-15 };
        assert_eq!(r.kind, m.kind, "{ext}");
        assert_eq!(r.connectivity, m.connectivity, "{ext}");
        for (a, b) in r.nodes.iter().zip(&m.nodes) {
            assert!(
                (0..D).all(|d| (a[d] - b[d]).abs() <= tol * (1.0 + b[d].abs())),
                "{ext}"
            );
        }
        assert_eq!(r.sets.node_sets, m.sets.node_sets, "{ext} node sets");
        assert_eq!(
            r.sets.element_sets, m.sets.element_sets,
            "{ext} element sets"
        );
        if ext == "inp" || ext == "msh" {
            assert_eq!(r.sets.surfaces, m.sets.surfaces, "{ext} surfaces");
        }
    }
    let feb = dir.join(format!("{name}.feb"));
    let w = write_mesh(&feb, m, None, &q);
    assert_eq!(w.is_ok(), D == 3);
}

#[test]
fn every_format_reads_back_with_its_sets() {
    round_trip(&two_cubes(), "hex");
    round_trip(&quads(), "quad");
    // Quadratic: mid-edge nodes in each program's order and back; sets carried.
    let hex20 = two_cubes().to_quadratic().unwrap();
    assert_eq!(hex20.nodes.len(), 12 + 20);
    round_trip(&hex20, "hex20");
    let tets = FeMesh {
        nodes: vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 1.0, 1.0],
        ],
        kind: ElementKind::Tet4,
        connectivity: vec![0, 1, 2, 3, 1, 2, 3, 4],
        sets: MeshSets {
            node_sets: [("TIP".to_string(), vec![3, 4])].into(),
            surfaces: [("BASE".to_string(), vec![(0, 0)])].into(),
            ..Default::default()
        },
    };
    let tet10 = tets.to_quadratic().unwrap();
    // The mid-edge node of 3-4 joins TIP; 9 edges, 9 mid-edge nodes.
    assert_eq!(tet10.nodes.len(), 5 + 9);
    assert_eq!(tet10.sets.node_sets["TIP"].len(), 3);
    round_trip(&tet10, "tet10");
}

#[test]
fn deck_nodes_are_replaced_and_nothing_else() {
    let tmp = tempfile::Builder::new()
        .prefix("atlasmesh-deck-")
        .tempdir()
        .unwrap();
    let dir = tmp.path();
    let m = two_cubes();
    let mut text = inp(&m, &dir.join("d.inp"));
    text.push_str("*MATERIAL, NAME=BONE\n*ELASTIC\n17000., 0.3\n*STEP\n*STATIC\n*END STEP\n");
    let p = dir.join("d.inp");
    std::fs::write(&p, &text).unwrap();
    let deck = crate::formats::read_inp(&p).unwrap();
    let moved: Vec<Point<3>> = m.nodes.iter().map(|p| [p[0] * 2.0, p[1], p[2]]).collect();
    let out = deck.with_nodes(&moved).unwrap();
    assert!(out.contains("*MATERIAL, NAME=BONE\n*ELASTIC\n17000., 0.3\n*STEP"));
    std::fs::write(&p, &out).unwrap();
    let again = crate::formats::read_inp(&p).unwrap();
    for (a, b) in again.mesh.nodes.iter().zip(&moved) {
        assert!((0..3).all(|d| (a[d] - b[d]).abs() < 1e-11 * (1.0 + b[d].abs())));
    }
    assert_eq!(again.mesh.connectivity, m.connectivity);
    assert_eq!(again.mesh.sets, m.sets);
}

#[test]
fn febio_deck_nodes_are_replaced_and_the_model_kept() {
    let m = two_cubes();
    let path = std::path::Path::new("model.feb");
    let text = super::febio::feb(&m, path).unwrap().replace(
        "  <Mesh>",
        "  <Material>\n    <material id=\"1\" name=\"bone\" type=\"isotropic elastic\"><E>17000</E></material>\n  </Material>\n  <Mesh>",
    );
    let deck = FebDeck::parse(path, &text).unwrap();
    assert_eq!(deck.mesh.nodes, m.nodes);
    assert_eq!(deck.mesh.connectivity, m.connectivity);
    let moved: Vec<Point<3>> = m
        .nodes
        .iter()
        .map(|p| [p[0] + 1.0, p[1], p[2] * 2.0])
        .collect();
    let out = Deck::Feb(deck).with_nodes(&moved).unwrap();
    let again = FebDeck::parse(path, &out).unwrap();
    assert_eq!(again.mesh.nodes, moved);
    assert_eq!(again.mesh.connectivity, m.connectivity);
    assert!(out.contains("<E>17000</E>") && out.contains("NodeSet") == text.contains("NodeSet"));
    // Not FEBio, or a broken mesh: errors naming the file.
    for bad in [
        "<x/>",
        "<febio_spec><Mesh><Nodes><node id=\"2\">0,0,0</node></Nodes></Mesh></febio_spec>",
        "<febio_spec><Mesh><Nodes><node id=\"1\">0,0</node></Nodes></Mesh></febio_spec>",
    ] {
        let e = FebDeck::parse(path, bad).unwrap_err().to_string();
        assert!(e.contains("model.feb"), "{e}");
    }
}

#[test]
fn outlines_written_as_vtp_and_vtk_read_back() {
    let t: Vec<[f64; 2]> = (0..12)
        .map(|k| {
            let a = k as f64 * std::f64::consts::TAU / 12.0;
            [3.0 * a.cos(), a.sin()]
        })
        .collect();
    let s = crate::geometry::Shape::polyline("o", t.clone(), true);
    let tmp = tempfile::Builder::new()
        .prefix("atlasmesh-outline-")
        .tempdir()
        .unwrap();
    let dir = tmp.path();
    for f in [ShapeFormat::Vtp, ShapeFormat::Vtk] {
        let p = dir.join(format!("o.{}", f.extension()));
        write_shape(&p, &s, f).unwrap();
        let r = read_outlines(&p, false).unwrap();
        assert_eq!(r.len(), 1);
        assert!(r[0].is_closed(), "{f:?}");
        assert_eq!(r[0].points, t, "{f:?}");
    }
    let e = write_shape(&dir.join("o.ply"), &s, ShapeFormat::Ply).unwrap_err();
    assert!(e.to_string().contains("vtp or vtk"), "{e}");
}

#[test]
fn repeated_gmsh_node_tags_and_legacy_offsets_not_from_zero_are_refused() {
    let m = crate::mesh::HexMesh::block(1);
    let text = super::gmsh::msh(&m);
    assert!(super::gmsh::parse_msh(std::path::Path::new("ok.msh"), text.as_bytes()).is_ok());
    let twice = text.replacen("3 1 0 8\n1\n2\n", "3 1 0 8\n1\n1\n", 1);
    assert_ne!(twice, text);
    let e = super::gmsh::parse_msh(std::path::Path::new("twice.msh"), twice.as_bytes())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("twice.msh") && e.contains("node tags are repeated"),
        "{e}"
    );
    let vtk = |offsets: &str| {
        format!(
            "# vtk DataFile Version 5.1\nt\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 float\n0 0 0 1 0 0 0 1 0 0 0 1\nCELLS 2 4\nOFFSETS vtktypeint64\n{offsets}\nCONNECTIVITY vtktypeint64\n0 1 2 3\nCELL_TYPES 1\n10\n"
        )
    };
    let ok = super::vtk_legacy::parse_vtk_unstructured(
        std::path::Path::new("ok.vtk"),
        vtk("0 4").as_bytes(),
    );
    assert_eq!(ok.unwrap().connectivity, vec![0, 1, 2, 3]);
    let e = super::vtk_legacy::parse_vtk_unstructured(
        std::path::Path::new("off.vtk"),
        vtk("1 4").as_bytes(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("off.vtk") && e.contains("offsets run from 1"),
        "{e}"
    );
}
