use super::*;
use std::path::Path;

/// A file named `name` in a temporary folder of its own; both are removed on drop.
pub(super) struct TmpFile {
    path: std::path::PathBuf,
    _dir: tempfile::TempDir,
}

impl std::ops::Deref for TmpFile {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.path
    }
}

impl AsRef<Path> for TmpFile {
    fn as_ref(&self) -> &Path {
        &self.path
    }
}

/// [`TmpFile`] `name` holding `content`, its folder named `PREFIXXXXXXX`.
pub(super) fn tmp_file(prefix: &str, name: &str, content: &[u8]) -> TmpFile {
    let dir = tempfile::Builder::new().prefix(prefix).tempdir().unwrap();
    let path = dir.path().join(name);
    std::fs::write(&path, content).unwrap();
    TmpFile { path, _dir: dir }
}

fn tmp(name: &str, content: &[u8]) -> TmpFile {
    tmp_file("atlasmesh-io-", name, content)
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

#[test]
fn csv_columns_are_found_by_name_and_mapped() {
    use crate::formats::csv_table::CsvColumns;
    let p = Path::new("pop.csv");
    // R's write.csv: quoted names, a row-number column, columns in another order.
    let r = "\"\",\"y\",\"x\",\"specimen\",\"lm\",\"sex\"\n\"1\",2,1,\"A\",0,\"f\"\n\"2\",4,3,\"A\",1,\"f\"\n\"3\",6,5,\"A\",2,\"f\"\n";
    let s = parse_long_csv(p, r, true).unwrap();
    assert_eq!(s.len(), 1);
    assert_eq!(s[0].name, "A");
    assert_eq!(s[0].points, vec![[1.0, 2.0], [3.0, 4.0], [5.0, 6.0]]);
    // Other names, mapped.
    let t = "Bone,Id,PX,PY\nB,1,0,0\nB,0,1,0\nB,2,0,1\n";
    let e = parse_long_csv(p, t, true).unwrap_err().to_string();
    assert!(e.contains("no x column") && e.contains("--columns"), "{e}");
    let cols: CsvColumns = "shape=Bone,point=Id,x=PX,y=PY".parse().unwrap();
    let s = parse_long_csv_with(p, t, true, &cols).unwrap();
    assert_eq!(s[0].points, vec![[1.0, 0.0], [0.0, 0.0], [0.0, 1.0]]);
    assert!(
        "colour=c"
            .parse::<CsvColumns>()
            .unwrap_err()
            .contains("roles")
    );
    let e = parse_long_csv_with(p, "shape,x,y\nA,0,0\n", true, &cols)
        .unwrap_err()
        .to_string();
    assert!(e.contains("no column \"bone\""), "{e}");
    // A z column: zero in 2D is fine, else a 3D point set.
    let z = "shape,point,x,y,z\nA,0,0,0,0\nA,1,1,0,0\nA,2,0,1,0\n";
    assert_eq!(parse_long_csv(p, z, true).unwrap()[0].points.len(), 3);
    let z3 = z.replace("A,2,0,1,0", "A,2,0,1,5");
    let e = parse_long_csv(p, &z3, true).unwrap_err().to_string();
    assert!(e.contains("3D points"), "{e}");
    let sets = crate::formats::parse_point_sets_csv(p, &z3, &CsvColumns::default()).unwrap();
    assert_eq!(sets[0].points[2], [0.0, 1.0, 5.0]);
    assert!(sets[0].facets.is_empty());
}

#[test]
fn landmark_csvs_say_their_index_base() {
    use crate::formats::landmarks::{Landmark, parse_landmarks_csv};
    let p = Path::new("lm.csv");
    let zero = parse_landmarks_csv::<2>(p, "shape,landmark,index\nA,0,4\nA,1,7\n").unwrap();
    let one =
        parse_landmarks_csv::<2>(p, "landmark,shape,index1,note\n0,A,5,x\n1,A,8,y\n").unwrap();
    type Named = crate::formats::landmarks::NamedLandmark<2>;
    let idx = |m: &std::collections::BTreeMap<String, Vec<Named>>| -> Vec<usize> {
        m["A"]
            .iter()
            .map(|(_, l)| match l {
                Landmark::Index(i) => *i,
                Landmark::At(_) => usize::MAX,
            })
            .collect()
    };
    assert_eq!(idx(&zero), vec![4, 7]);
    assert_eq!(idx(&one), idx(&zero));
    let e = parse_landmarks_csv::<2>(p, "shape,landmark,index1\nA,0,0\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("1-based"), "{e}");
}

#[test]
fn csv_quotes_a_split_would_misread_and_columns_named_twice_are_refused() {
    use crate::formats::csv_table::CsvColumns;
    let p = Path::new("r.csv");
    let comma = "shape,point,x,y\n\"s,1\",0,1,2\n";
    let e = parse_long_csv(p, comma, true).unwrap_err().to_string();
    assert!(e.contains("r.csv:2") && e.contains("quoted field"), "{e}");
    let escaped = "shape,point,x,y\n\"a\"\"b\",0,1,2\n";
    assert!(parse_long_csv(p, escaped, true).is_err());
    let twice = "shape,point,x,x\nA,0,1,2\n";
    let e = parse_long_csv(p, twice, true).unwrap_err().to_string();
    assert!(e.contains("\"x\" twice"), "{e}");
    let e = "x=PX,y=PX".parse::<CsvColumns>().unwrap_err();
    assert!(e.contains("both name the column"), "{e}");
    // R's quoting of plain names still reads.
    let r = "\"shape\",\"point\",\"x\",\"y\"\n\"A\",0,1,2\n\"A\",1,3,4\n\"A\",2,5,7\n";
    assert_eq!(parse_long_csv(p, r, true).unwrap()[0].points.len(), 3);
}
