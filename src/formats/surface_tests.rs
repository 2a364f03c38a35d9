use super::*;
use crate::geometry::{Shape, is_closed_surface, prepare_surface, signed_volume};

fn tetra() -> Shape<3> {
    Shape {
        name: "t".into(),
        points: vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ],
        // Mixed orientation on purpose.
        facets: vec![[0, 1, 2], [0, 1, 3], [1, 2, 3], [0, 2, 3]],
        landmarks: Vec::new(),
    }
}

#[test]
fn a_closed_surface_is_oriented_outwards() {
    let s = prepare_surface(tetra()).unwrap();
    assert!(signed_volume(&s) > 0.0);
    assert!((signed_volume(&s) - 1.0 / 6.0).abs() < 1e-12);
    assert!(is_closed_surface(&s));
}

#[test]
fn ply_and_stl_round_trip() {
    let s = prepare_surface(tetra()).unwrap();
    let tmp = tempfile::Builder::new()
        .prefix("atlasmesh-surf-")
        .tempdir()
        .unwrap();
    let dir = tmp.path();
    for ext in ["ply", "stl"] {
        let p = dir.join(format!("t.{ext}"));
        if ext == "ply" {
            write_ply(&p, &s).unwrap();
        } else {
            write_stl(&p, &s).unwrap();
        }
        let r = read_surface(&p).unwrap();
        assert_eq!(r.points.len(), 4, "{ext}");
        assert_eq!(r.facets.len(), 4, "{ext}");
        assert!((signed_volume(&r) - 1.0 / 6.0).abs() < 1e-6, "{ext}");
    }
}

#[test]
fn legacy_vtk_polygons_are_read_as_a_surface() {
    let tmp = tempfile::Builder::new()
        .prefix("atlasmesh-vtk3-")
        .tempdir()
        .unwrap();
    let dir = tmp.path();
    let p = dir.join("t.vtk");
    std::fs::write(
        &p,
        "# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\nPOINTS 4 float\n0 0 0 1 0 0 0 1 0 0 0 1\nPOLYGONS 4 16\n3 0 1 2\n3 0 1 3\n3 1 2 3\n3 0 2 3\n",
    )
    .unwrap();
    let s = read_surface(&p).unwrap();
    assert_eq!((s.points.len(), s.facets.len()), (4, 4));
    assert!((signed_volume(&s) - 1.0 / 6.0).abs() < 1e-9);
}

#[test]
fn non_manifold_and_truncated_inputs_are_refused() {
    let mut s = tetra();
    s.points.push([1.0, 1.0, 1.0]);
    s.facets.push([0, 1, 4]);
    let e = prepare_surface(s).unwrap_err().to_string();
    assert!(e.contains("edge-manifold"), "{e}");
    let tmp = tempfile::Builder::new()
        .prefix("atlasmesh-trunc-")
        .tempdir()
        .unwrap();
    let dir = tmp.path();
    let p = dir.join("t.ply");
    write_ply(&p, &prepare_surface(tetra()).unwrap()).unwrap();
    let b = std::fs::read(&p).unwrap();
    std::fs::write(&p, &b[..b.len() - 7]).unwrap();
    let e = read_surface(&p).unwrap_err().to_string();
    assert!(e.contains("truncated") && e.contains("t.ply"), "{e}");
}
