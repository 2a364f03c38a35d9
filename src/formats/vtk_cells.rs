//! VTK cells into atlasmesh's shapes and meshes, for both VTK readers (legacy and XML): the
//! polygons or lines of polydata, the outline a chain of lines makes, and the FE mesh of an
//! unstructured grid's cells of one kind (with `set_NAME` point and cell data as sets).

use super::helpers::check_mesh;
use super::helpers::stem;
use crate::error::{Error, Result};
use crate::geometry::Shape;
use crate::mesh::{ElementKind, FeMesh, MeshSets};
use std::path::Path;

/// Points and cells of VTK polydata (legacy POLYDATA or VTP).
#[derive(Debug, Default)]
pub struct VtkPolyData {
    /// The points.
    pub points: Vec<[f64; 3]>,
    /// The line and poly-line cells (point indices).
    pub lines: Vec<Vec<usize>>,
    /// The polygon cells, and the triangles of triangle strips (point indices).
    pub polygons: Vec<Vec<usize>>,
}

impl VtkPolyData {
    /// Adds the triangles of a triangle strip, every other one flipped so that all keep the
    /// strip's orientation.
    pub(crate) fn push_strip(&mut self, strip: &[usize]) {
        for i in 2..strip.len() {
            let t = if i % 2 == 0 {
                vec![strip[i - 2], strip[i - 1], strip[i]]
            } else {
                vec![strip[i - 1], strip[i - 2], strip[i]]
            };
            self.polygons.push(t);
        }
    }
}

/// Cells as VTK lays them out: `connectivity`, the end `offsets` of each cell in it.
pub(crate) fn split_cells(
    path: &Path,
    conn: &[i64],
    offsets: &[i64],
    points: usize,
) -> Result<Vec<Vec<usize>>> {
    if offsets.len() > super::MAX_COUNT {
        return Err(Error::parse(
            path,
            0,
            format!(
                "{} cells, beyond the limit of {}",
                offsets.len(),
                super::MAX_COUNT
            ),
        ));
    }
    let mut cells = Vec::with_capacity(offsets.len());
    let mut prev = 0usize;
    for (c, &o) in offsets.iter().enumerate() {
        let o = index(path, o, conn.len() + 1, "a cell offset")?;
        if o < prev {
            return Err(Error::parse(
                path,
                0,
                format!("the cell offsets decrease at cell {c}"),
            ));
        }
        // An empty cell holds nothing; refusing it also bounds the cells by the
        // connectivity's length (an `offsets` array of zeros would make millions).
        if o == prev {
            return Err(Error::parse(
                path,
                0,
                format!("cell {c} has no points (its offset repeats the previous one)"),
            ));
        }
        cells.push(
            conn[prev..o]
                .iter()
                .map(|&v| index(path, v, points, "a point index"))
                .collect::<Result<_>>()?,
        );
        prev = o;
    }
    Ok(cells)
}

/// VTK cell type numbers as read (values outside 0..=255 become 255, a type VTK does not
/// define).
pub(crate) fn cell_types(v: impl IntoIterator<Item = i64>) -> Vec<u8> {
    v.into_iter()
        .map(|t| u8::try_from(t).unwrap_or(255))
        .collect()
}

/// `v` as an index below `n`.
fn index(path: &Path, v: i64, n: usize, what: &str) -> Result<usize> {
    if let Ok(i) = usize::try_from(v)
        && i < n
    {
        Ok(i)
    } else {
        Err(Error::parse(
            path,
            0,
            format!("{what} {v} is out of range (0..{n})"),
        ))
    }
}

/// The 2D outline of polydata's lines: points reordered along the chain of segments; every
/// point has at most two neighbours and the segments form one chain or one loop, in a plane
/// of constant z.
pub(crate) fn outline_from_polydata(path: &Path, vtk: &VtkPolyData) -> Result<Shape<2>> {
    if !vtk.polygons.is_empty() {
        return Err(Error::parse(
            path,
            0,
            "the file holds polygons: this is a 3D surface, a 2D outline (lines) was expected",
        ));
    }
    let z0 = vtk.points.first().map_or(0.0, |p| p[2]);
    if vtk
        .points
        .iter()
        .any(|p| (p[2] - z0).abs() > 1e-9 * (1.0 + z0.abs()))
    {
        return Err(Error::parse(
            path,
            0,
            "the points have varying z: this is a 3D shape, a 2D outline was expected",
        ));
    }
    let n = vtk.points.len();
    let mut adj: Vec<Vec<usize>> = vec![Vec::new(); n];
    let mut nseg = 0;
    for l in &vtk.lines {
        for w in l.windows(2) {
            if w[0] != w[1] {
                adj[w[0]].push(w[1]);
                adj[w[1]].push(w[0]);
                nseg += 1;
            }
        }
    }
    if nseg == 0 {
        return Err(Error::parse(
            path,
            0,
            "no lines: an outline needs line segments",
        ));
    }
    if let Some(i) = adj.iter().position(|a| a.len() > 2) {
        return Err(Error::parse(
            path,
            0,
            format!(
                "point {i} has {} neighbours: the lines branch; one chain or loop is expected",
                adj[i].len()
            ),
        ));
    }
    let used: Vec<usize> = (0..n).filter(|&i| !adj[i].is_empty()).collect();
    let start = used
        .iter()
        .copied()
        .find(|&i| adj[i].len() == 1)
        .unwrap_or(used[0]);
    let closed = adj[start].len() == 2;
    let mut order = vec![start];
    let mut prev = usize::MAX;
    let mut cur = start;
    loop {
        let next = adj[cur]
            .iter()
            .copied()
            .find(|&j| j != prev && (order.len() < 2 || j != order[order.len() - 2]));
        match next {
            Some(j) if j != start => {
                order.push(j);
                prev = cur;
                cur = j;
            }
            _ => break,
        }
        if order.len() > n {
            break;
        }
    }
    if order.len() != used.len() {
        return Err(Error::parse(
            path,
            0,
            format!(
                "the lines form several pieces ({} of {} points in the first); one outline is expected",
                order.len(),
                used.len()
            ),
        ));
    }
    let pts = order
        .iter()
        .map(|&i| [vtk.points[i][0], vtk.points[i][1]])
        .collect();
    Ok(Shape::polyline(stem(path), pts, closed))
}

/// The dimension of VTK cell type `t` (`None` for types VTK does not define).
fn cell_dimension(t: u8) -> Option<usize> {
    Some(match t {
        1 | 2 => 0,
        3 | 4 | 21 | 35 | 68 => 1,
        5..=9 | 22 | 23 | 28 | 30 | 34 | 36 | 37 | 69 | 70 => 2,
        10..=16 | 24..=27 | 29 | 31..=33 | 38..=42 | 71..=75 => 3,
        _ => return None,
    })
}

/// A VTK cell type's name, for messages.
fn cell_name(t: u8) -> String {
    let n = match t {
        1 => "vertex",
        2 => "poly-vertex",
        3 => "line",
        4 => "poly-line",
        5 => "triangle",
        6 => "triangle strip",
        7 => "polygon",
        8 => "pixel",
        9 => "quadrilateral",
        10 => "tetrahedron",
        11 => "voxel",
        12 => "hexahedron",
        13 => "wedge",
        14 => "pyramid",
        21 => "quadratic edge",
        22 => "quadratic triangle",
        23 => "quadratic quadrilateral",
        24 => "quadratic tetrahedron",
        25 => "quadratic hexahedron",
        42 => "polyhedron",
        _ => "cell",
    };
    format!("{n} ({t})")
}

/// Named point or cell data arrays (one value per point or cell).
pub(crate) type DataArrays = Vec<(String, Vec<f64>)>;

/// The arrays `set_NAME` of `data` as (NAME, values), each checked to hold `n` values.
fn set_arrays<'a>(
    path: &Path,
    data: &'a DataArrays,
    n: usize,
) -> Result<Vec<(&'a str, &'a [f64])>> {
    data.iter()
        .filter_map(|(name, v)| name.strip_prefix("set_").map(|set| (name, set, v)))
        .map(|(name, set, v)| {
            if v.len() == n {
                Ok((set, v.as_slice()))
            } else {
                Err(Error::parse(
                    path,
                    0,
                    format!("{name} has {} values, {n} expected", v.len()),
                ))
            }
        })
        .collect()
}

/// The FE mesh of an unstructured grid: the cells of the highest dimension, which must be of
/// one kind atlasmesh meshes with (triangles, quadrilaterals, tetrahedra, hexahedra, and their
/// quadratic forms, in VTK's node order); lower-dimensional cells (vertices, lines, boundary
/// faces) are dropped. Point and cell data named `set_NAME` (non-zero for members) become
/// node and element sets.
pub(crate) fn mesh_from_cells(
    path: &Path,
    nodes: Vec<[f64; 3]>,
    cells: &[Vec<usize>],
    types: &[u8],
    point_data: &DataArrays,
    cell_data: &DataArrays,
) -> Result<FeMesh<3>> {
    if types.len() != cells.len() {
        return Err(Error::parse(
            path,
            0,
            format!("{} cell types for {} cells", types.len(), cells.len()),
        ));
    }
    if let Some(&t) = types.iter().find(|&&t| cell_dimension(t).is_none()) {
        return Err(Error::parse(path, 0, format!("unknown VTK cell type {t}")));
    }
    let top = types
        .iter()
        .filter_map(|&t| cell_dimension(t))
        .max()
        .ok_or_else(|| Error::parse(path, 0, "the mesh has no cells"))?;
    let mut found: std::collections::BTreeMap<u8, usize> = Default::default();
    for &t in types.iter().filter(|&&t| cell_dimension(t) == Some(top)) {
        *found.entry(t).or_default() += 1;
    }
    let listed = || {
        found
            .iter()
            .map(|(&t, n)| format!("{n} {}", cell_name(t)))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let kind = match (found.len(), found.keys().next().copied()) {
        (1, Some(t)) => ElementKind::from_vtk_type(t).filter(|k| k.dimension() == top),
        _ => None,
    }
    .ok_or_else(|| {
        Error::parse(
            path,
            0,
            format!(
                "the {top}D cells are {}; one kind of triangles, quadrilaterals, tetrahedra or hexahedra (linear or quadratic) is read",
                listed()
            ),
        )
    })?;
    let k = kind.nodes();
    let kept: Vec<usize> = (0..cells.len())
        .filter(|&c| types[c] == kind.vtk_type())
        .collect();
    let mut connectivity = Vec::with_capacity(kept.len() * k);
    for &c in &kept {
        if cells[c].len() != k {
            return Err(Error::parse(
                path,
                0,
                format!(
                    "cell {c} ({}) has {} nodes, not {k}",
                    kind.name(),
                    cells[c].len()
                ),
            ));
        }
        connectivity.extend_from_slice(&cells[c]);
    }
    let mut sets = MeshSets::default();
    for (set, v) in set_arrays(path, point_data, nodes.len())? {
        let members = (0..v.len()).filter(|&i| v[i] != 0.0).collect();
        sets.node_sets.insert(set.to_string(), members);
    }
    for (set, v) in set_arrays(path, cell_data, cells.len())? {
        let members = kept
            .iter()
            .enumerate()
            .filter(|&(_, &c)| v[c] != 0.0)
            .map(|(e, _)| e)
            .collect();
        sets.element_sets.insert(set.to_string(), members);
    }
    check_mesh(path, &nodes, kind, &connectivity, &sets)?;
    Ok(FeMesh {
        nodes,
        kind,
        connectivity,
        sets,
    })
}
