use super::*;
use crate::geometry::Shape;
use crate::mesh::{ElementKind, FeMesh};

#[test]
fn written_vtp_and_vtu_read_back() {
    let dir = std::env::temp_dir().join(format!("atlasmesh-xml-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let s = Shape::<3> {
        name: "t".into(),
        points: vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ],
        facets: vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
        landmarks: Vec::new(),
    };
    let p = dir.join("t.vtp");
    crate::formats::write_vtp(&p, &s).unwrap();
    let v = read_vtp(&p).unwrap();
    assert_eq!(v.points, s.points);
    assert_eq!(
        v.polygons,
        s.facets.iter().map(|f| f.to_vec()).collect::<Vec<_>>()
    );
    let cube = FeMesh {
        nodes: vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 1.0],
            [1.0, 1.0, 1.0],
            [0.0, 1.0, 1.0],
        ],
        kind: ElementKind::Hex8,
        connectivity: (0..8).collect(),
        sets: Default::default(),
    };
    let p = dir.join("c.vtu");
    crate::formats::write_vtu(&p, &cube, None).unwrap();
    let m = read_vtu(&p).unwrap();
    assert_eq!(m.nodes, cube.nodes);
    assert_eq!(m.connectivity, cube.connectivity);
    // Truncated: a clear error naming the file.
    let t = std::fs::read_to_string(&p).unwrap();
    std::fs::write(&p, &t[..t.len() / 2]).unwrap();
    let e = read_vtu(&p).unwrap_err().to_string();
    assert!(e.contains("c.vtu") && e.contains("not closed"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}
