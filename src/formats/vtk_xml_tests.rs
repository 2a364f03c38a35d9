use super::*;
use crate::geometry::Shape;
use crate::mesh::{ElementKind, FeMesh};

#[test]
fn written_vtp_and_vtu_read_back() {
    let tmp = tempfile::Builder::new()
        .prefix("atlasmesh-xml-")
        .tempdir()
        .unwrap();
    let dir = tmp.path();
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
}

/// Arrays larger than a compression block (a bar of 4 000 hexahedra: 384 kB of coordinates)
/// and a 2D outline written compressed, read back to the bit, sets included; the file smaller
/// than its arrays.
#[test]
fn compressed_arrays_of_several_blocks_read_back() {
    let tmp = tempfile::Builder::new()
        .prefix("atlasmesh-xml-")
        .tempdir()
        .unwrap();
    let n = 4000;
    let mut nodes = Vec::new();
    for i in 0..=n {
        for (y, z) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
            nodes.push([i as f64 * 0.37 + 1e-9 * (i * i) as f64, y, z]);
        }
    }
    let connectivity: Vec<usize> = (0..n)
        .flat_map(|e| {
            let a = 4 * e;
            [a, a + 4, a + 5, a + 1, a + 3, a + 7, a + 6, a + 2]
        })
        .collect();
    let mut bar = FeMesh {
        nodes,
        kind: ElementKind::Hex8,
        connectivity,
        sets: Default::default(),
    };
    bar.sets
        .node_sets
        .insert("END".into(), (4 * n..4 * n + 4).collect());
    bar.sets.element_sets.insert("FIRST".into(), vec![0, 1]);
    let p = tmp.path().join("bar.vtu");
    crate::formats::write_vtu(&p, &bar, None).unwrap();
    let text = std::fs::read_to_string(&p).unwrap();
    assert!(text.contains("compressor=\"vtkZLibDataCompressor\""));
    let raw = bar.nodes.len() * 24 + bar.connectivity.len() * 8;
    assert!(
        text.len() < raw,
        "{} bytes for {raw} bytes of arrays",
        text.len()
    );
    let m = read_vtu(&p).unwrap();
    assert_eq!(m.nodes, bar.nodes);
    assert_eq!(m.connectivity, bar.connectivity);
    assert_eq!(m.sets.node_sets["END"], bar.sets.node_sets["END"]);
    assert_eq!(m.sets.element_sets["FIRST"], vec![0, 1]);

    let outline = Shape::<2> {
        name: "o".into(),
        points: (0..5000)
            .map(|i| {
                let t = i as f64 * std::f64::consts::TAU / 5000.0;
                [t.cos(), 0.5 * t.sin()]
            })
            .collect(),
        facets: (0..5000).map(|i| [i, (i + 1) % 5000]).collect(),
        landmarks: Vec::new(),
    };
    let p = tmp.path().join("o.vtp");
    crate::formats::write_vtp(&p, &outline).unwrap();
    let v = read_vtp(&p).unwrap();
    assert_eq!(v.points.len(), 5000);
    assert!(
        v.points
            .iter()
            .zip(&outline.points)
            .all(|(a, b)| a[0] == b[0] && a[1] == b[1] && a[2] == 0.0)
    );
    assert_eq!(v.lines.len(), 5000);
}

/// A VTU of one hexahedron whose eight point-data arrays share one appended zlib block that
/// inflates to 40 MB of bytes (320 MB as values) each: refused before it is inflated, by the
/// file's decoding budget, with a message that says why.
#[test]
fn arrays_sharing_one_inflating_block_are_refused_by_the_budget() {
    use std::io::Write as _;
    let n: u32 = 40 << 20;
    let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::fast());
    z.write_all(&vec![0u8; n as usize]).unwrap();
    let packed = z.finish().unwrap();
    let mut block = Vec::new();
    for w in [1, n, n, packed.len() as u32] {
        block.extend(w.to_le_bytes());
    }
    block.extend(&packed);
    let sets: String = (b'a'..=b'h')
        .map(|c| {
            format!(
                "<DataArray type=\"UInt8\" Name=\"set_{}\" format=\"appended\" offset=\"0\"/>",
                c as char
            )
        })
        .collect();
    let mut file = format!(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt32\" compressor=\"vtkZLibDataCompressor\">\n<UnstructuredGrid><Piece NumberOfPoints=\"8\" NumberOfCells=\"1\">\n<PointData>{sets}</PointData>\n<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">0 0 0 1 0 0 1 1 0 0 1 0 0 0 1 1 0 1 1 1 1 0 1 1</DataArray></Points>\n<Cells><DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">0 1 2 3 4 5 6 7</DataArray><DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">8</DataArray><DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">12</DataArray></Cells>\n</Piece></UnstructuredGrid>\n<AppendedData encoding=\"raw\">_"
    )
    .into_bytes();
    file.extend(&block);
    file.extend(b"\n</AppendedData>\n</VTKFile>\n");
    assert!(file.len() < 1 << 20);
    let e = parse_vtu(std::path::Path::new("bomb.vtu"), &file)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("bomb.vtu") && e.contains("decompression bomb"),
        "{e}"
    );
}

/// A hexahedron's VTU with the connectivity stored as `ty` holding `conn`.
fn hex_vtu(ty: &str, conn: &str) -> Vec<u8> {
    format!(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\">\n<UnstructuredGrid><Piece NumberOfPoints=\"8\" NumberOfCells=\"1\">\n<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">0 0 0 1 0 0 1 1 0 0 1 0 0 0 1 1 0 1 1 1 1 0 1 1</DataArray></Points>\n<Cells><DataArray type=\"{ty}\" Name=\"connectivity\" format=\"ascii\">{conn}</DataArray><DataArray type=\"UInt8\" Name=\"offsets\" format=\"ascii\">8</DataArray><DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">12</DataArray></Cells>\n</Piece></UnstructuredGrid>\n</VTKFile>\n"
    )
    .into_bytes()
}

#[test]
fn cell_arrays_are_read_as_integers() {
    let path = std::path::Path::new("cells.vtu");
    // Any integer type, small ones too.
    for ty in ["UInt8", "Int16", "Int32", "UInt64"] {
        let m = parse_vtu(path, &hex_vtu(ty, "0 1 2 3 4 5 6 7")).unwrap();
        assert_eq!(m.connectivity, vec![0, 1, 2, 3, 4, 5, 6, 7], "{ty}");
    }
    // An index that only rounds to a valid one through f64 (2^53 + 1 → 2^53) and a fraction
    // are refused, naming the value.
    let e = parse_vtu(path, &hex_vtu("Int64", "0 1 2 3 4 5 6 9007199254740993"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("9007199254740993") && e.contains("cells.vtu"),
        "{e}"
    );
    let e = parse_vtu(path, &hex_vtu("Int64", "0 1 2 3 4 5 6 6.5"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("\"6.5\" is not an integer"), "{e}");
}
