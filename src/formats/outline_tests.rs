use super::*;

fn tmp(name: &str, content: &[u8]) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("atlasmesh-io-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, content).unwrap();
    p
}

#[test]
fn ascii_vtk_loop_is_read_in_chain_order() {
    let p = tmp(
        "sq.vtk",
        b"# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 4 float\n0 0 0 1 1 0 1 0 0 0 1 0\nLINES 4 12\n2 0 2\n2 2 1\n2 3 0\n2 1 3\n",
    );
    let s = read_vtk_outline(&p).unwrap();
    assert!(s.is_closed());
    assert_eq!(
        s.points,
        vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
    );
}

#[test]
fn binary_vtk_truncated_is_an_error() {
    let mut b =
        b"# vtk DataFile Version 3.0\nx\nBINARY\nDATASET POLYDATA\nPOINTS 4 float\n".to_vec();
    b.extend_from_slice(&[0u8; 20]);
    let p = tmp("t.vtk", &b);
    let e = read_vtk_outline(&p).unwrap_err().to_string();
    assert!(e.contains("truncated") && e.contains("t.vtk"), "{e}");
}

#[test]
fn blank_lines_separate_the_shapes_of_a_text_file() {
    let p = tmp(
        "blocks.txt",
        b"# cells\n0 0\n1 0\n0 1\n\n\n2 2\n3 2\n# comment\n2 3\n3 3\n",
    );
    let s = read_outlines(&p, true).unwrap();
    assert_eq!(s.len(), 2);
    assert_eq!((s[0].name.as_str(), s[0].points.len()), ("blocks-000", 3));
    assert_eq!((s[1].name.as_str(), s[1].points.len()), ("blocks-001", 4));
    let one = tmp("one.txt", b"0 0\n1 0\n0 1\n");
    assert_eq!(read_outlines(&one, true).unwrap()[0].name, "one");
}

#[test]
fn csv_with_a_gap_in_indices_is_an_error() {
    let p = tmp(
        "gap.csv",
        b"shape,point,x,y\n0,0,1,2\n0,2,3,4\n0,1,5,6\n0,4,1,1\n",
    );
    let e = read_long_csv(&p, false).unwrap_err().to_string();
    assert!(e.contains("gap.csv") && e.contains("index 4"), "{e}");
}
