//! What the two Gmsh readers (ASCII in `gmsh`, binary in `gmsh_binary`) fill before the
//! mesh is assembled, and Gmsh's element-type table.

use crate::error::{Error, Result};
use crate::geometry::Point;
use std::collections::HashMap;
use std::path::Path;

/// A Gmsh element as read: dimension, type, node tags, physical tags, element tag.
pub(crate) type MshElement = (usize, u32, Vec<i64>, Vec<i64>, i64);

/// A Gmsh file as read, before the mesh is assembled.
#[derive(Default)]
pub(crate) struct Parsed {
    /// Physical names by (dimension, tag).
    pub names: HashMap<(usize, i64), String>,
    /// Node index by node tag.
    pub node_index: HashMap<i64, usize>,
    pub nodes: Vec<Point<3>>,
    pub elements: Vec<MshElement>,
    /// The line of `$Elements`, for messages (0 in binary files).
    pub line: usize,
}

/// The physical names of a `$PhysicalNames` section's lines (the count line first).
pub(crate) fn physical_names(
    path: &Path,
    ln: usize,
    body: &[&str],
) -> Result<HashMap<(usize, i64), String>> {
    let mut names = HashMap::new();
    for (k, l) in body.iter().enumerate().skip(1) {
        let mut it = l.trim().splitn(3, char::is_whitespace);
        let (Some(d), Some(t), Some(n)) = (it.next(), it.next(), it.next()) else {
            return Err(Error::parse(
                path,
                ln + k,
                "a physical name needs dim, tag, name",
            ));
        };
        let d: usize = d
            .parse()
            .map_err(|_| Error::parse(path, ln + k, "bad dimension"))?;
        let t: i64 = t
            .parse()
            .map_err(|_| Error::parse(path, ln + k, "bad tag"))?;
        names.insert((d, t), n.trim().trim_matches('"').to_string());
    }
    Ok(names)
}

/// The dimension of Gmsh element type `t` (`None` when not known).
pub(crate) fn gmsh_dimension(t: u32) -> Option<usize> {
    Some(match t {
        15 => 0,
        1 | 8 | 26 | 27 | 28 => 1,
        2 | 3 | 9 | 10 | 16 | 20..=25 | 36 | 37 => 2,
        4..=7 | 11..=14 | 17..=19 | 29..=35 | 92 | 93 => 3,
        _ => return None,
    })
}

/// The node count of Gmsh element type `t` (`None` when not known).
pub(crate) fn gmsh_nodes(t: u32) -> Option<usize> {
    Some(match t {
        15 => 1,
        1 => 2,
        2 | 8 => 3,
        3 | 4 => 4,
        5 => 8,
        6 | 9 => 6,
        7 => 5,
        10 => 9,
        11 | 21 => 10,
        12 => 27,
        13 => 18,
        14 => 14,
        16 => 8,
        17 => 20,
        18 => 15,
        19 => 13,
        20 => 9,
        26 => 4,
        29 => 20,
        36 => 16,
        _ => return None,
    })
}
