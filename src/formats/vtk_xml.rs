//! VTK XML: VTP (polydata: outlines and surfaces) and VTU (unstructured grids: FE meshes with
//! their sets and quality) read and written.

use super::vtk_cells::{DataArrays, VtkPolyData, cell_types, mesh_from_cells, split_cells};
use super::vtk_xml_read::{ArraySpec, Document, Piece};
use crate::error::{Error, Result};
use crate::geometry::{Point, Shape};
use crate::mesh::FeMesh;
use crate::mesh::quality::mesh_quality;
use std::fmt::Write as _;
use std::path::Path;

/// The array `name` (the first array when `None`) of section `tag` in `piece`, not decoded.
fn spec<'p>(
    doc: &Document,
    piece: &'p Piece,
    tag: &str,
    name: Option<&str>,
) -> Result<&'p ArraySpec> {
    let path = doc.path();
    let s = piece
        .section(tag)
        .ok_or_else(|| Error::parse(path, 0, format!("no <{tag}> section")))?;
    s.arrays
        .iter()
        .find(|a| name.is_none_or(|n| a.name == n))
        .ok_or_else(|| {
            Error::parse(
                path,
                0,
                format!(
                    "no DataArray{} in <{tag}>",
                    name.map(|n| format!(" '{n}'")).unwrap_or_default()
                ),
            )
        })
}

/// The values of the array `name` (the first array when `None`) of section `tag` in `piece`.
fn array(doc: &Document, piece: &Piece, tag: &str, name: Option<&str>) -> Result<Vec<f64>> {
    doc.values(spec(doc, piece, tag, name)?, tag)
}

/// The integer array `name` of section `tag` in `piece`, kept as integers.
fn integers(doc: &Document, piece: &Piece, tag: &str, name: &str) -> Result<Vec<i64>> {
    doc.integers(spec(doc, piece, tag, Some(name))?, tag)
}

/// The points of a piece (checked against its `NumberOfPoints`, finite).
fn points(doc: &Document, piece: &Piece) -> Result<Vec<Point<3>>> {
    let path = doc.path();
    let v = array(doc, piece, "Points", None)?;
    if v.len() != 3 * piece.points {
        return Err(Error::parse(
            path,
            0,
            format!(
                "<Points> holds {} coordinates for NumberOfPoints=\"{}\" (truncated?)",
                v.len(),
                piece.points
            ),
        ));
    }
    if v.iter().any(|c| !c.is_finite()) {
        return Err(Error::parse(
            path,
            0,
            "a point has a NaN or infinite coordinate",
        ));
    }
    Ok(v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
}

/// The cells of section `tag` (`connectivity` and `offsets`), empty when the piece has none.
fn cells(doc: &Document, piece: &Piece, tag: &str, points: usize) -> Result<Vec<Vec<usize>>> {
    if piece.section(tag).is_none_or(|s| s.arrays.is_empty()) {
        return Ok(Vec::new());
    }
    let conn = integers(doc, piece, tag, "connectivity")?;
    let offs = integers(doc, piece, tag, "offsets")?;
    split_cells(doc.path(), &conn, &offs, points)
}

/// The data arrays of section `tag` (`PointData`, `CellData`) whose names start with `prefix`.
fn data(doc: &Document, piece: &Piece, tag: &str, prefix: &str) -> Result<DataArrays> {
    let Some(s) = piece.section(tag) else {
        return Ok(Vec::new());
    };
    s.arrays
        .iter()
        .filter(|a| a.name.starts_with(prefix))
        .map(|a| Ok((a.name.clone(), doc.values(a, tag)?)))
        .collect()
}

/// Reads the points, polygons and lines of a VTK XML PolyData file (`.vtp`) as VTK, ParaView,
/// PyVista and meshio write it: ASCII, base64 or appended raw data, compressed with zlib or
/// LZ4 or not (see docs/formats.md). Triangle strips become triangles; vertices are
/// dropped; several pieces are joined.
pub fn read_vtp(path: &Path) -> Result<VtkPolyData> {
    let bytes = crate::formats::read_input(path)?;
    parse_vtp(path, &bytes)
}

/// [`read_vtp`] of a file's bytes (`path` only names the file in messages): no file is read.
pub fn parse_vtp(path: &Path, bytes: &[u8]) -> Result<VtkPolyData> {
    let doc = Document::parse(path, bytes)?;
    if doc.kind != "PolyData" {
        return Err(Error::parse(
            path,
            1,
            format!("a VTK XML {:?} file, not PolyData", doc.kind),
        ));
    }
    let mut out = VtkPolyData::default();
    for piece in &doc.pieces {
        let base = out.points.len();
        let pts = points(&doc, piece)?;
        let shift = |c: Vec<usize>| c.into_iter().map(|i| i + base).collect::<Vec<_>>();
        for p in cells(&doc, piece, "Polys", pts.len())? {
            out.polygons.push(shift(p));
        }
        for s in cells(&doc, piece, "Strips", pts.len())? {
            out.push_strip(&shift(s));
        }
        for l in cells(&doc, piece, "Lines", pts.len())? {
            out.lines.push(shift(l));
        }
        out.points.extend(pts);
    }
    if out.points.is_empty() {
        return Err(Error::parse(path, 0, "the file has no points"));
    }
    Ok(out)
}

/// Reads an FE mesh from a VTK XML UnstructuredGrid file (`.vtu`), encoded as [`read_vtp`]
/// reads: the cells of the highest dimension, of one kind (VTK's 5, 9, 10, 12, 24 or 25:
/// triangles, quadrilaterals, tetrahedra, hexahedra and their quadratic forms, in VTK's node
/// order), lower-dimensional cells dropped. Point and cell data `set_NAME` (0/1, as
/// [`crate::formats::write_vtu`] writes them) are read back as node and element sets.
pub fn read_vtu(path: &Path) -> Result<FeMesh<3>> {
    let bytes = crate::formats::read_input(path)?;
    parse_vtu(path, &bytes)
}

/// [`read_vtu`] of a file's bytes (`path` only names the file in messages): no file is read.
pub fn parse_vtu(path: &Path, bytes: &[u8]) -> Result<FeMesh<3>> {
    let doc = Document::parse(path, bytes)?;
    if doc.kind != "UnstructuredGrid" {
        return Err(Error::parse(
            path,
            1,
            format!("a VTK XML {:?} file, not UnstructuredGrid", doc.kind),
        ));
    }
    let piece = match doc.pieces.as_slice() {
        [p] => p,
        [] => return Err(Error::parse(path, 0, "the file has no <Piece>")),
        _ => {
            return Err(Error::parse(
                path,
                0,
                format!("{} pieces; a mesh in one piece is read", doc.pieces.len()),
            ));
        }
    };
    let nodes = points(&doc, piece)?;
    let cells = cells(&doc, piece, "Cells", nodes.len())?;
    let types = cell_types(integers(&doc, piece, "Cells", "types")?);
    let point_data = data(&doc, piece, "PointData", "set_")?;
    let cell_data = data(&doc, piece, "CellData", "set_")?;
    mesh_from_cells(path, nodes, &cells, &types, &point_data, &cell_data)
}

/// The `VTKFile` element's attributes of every file written here: little-endian binary arrays
/// with 64-bit headers, compressed with zlib as VTK, ParaView and meshio write them.
const VTK_FILE_ATTRIBUTES: &str = "version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\" compressor=\"vtkZLibDataCompressor\"";

/// The uncompressed size of the blocks an array is compressed in (VTK's default is 32 KiB;
/// larger blocks compress a little better and cost nothing to a reader).
const BLOCK_BYTES: usize = 1 << 16;

/// The zlib level of the arrays written: 1, the fastest. On a fitted femur's mesh (57 000
/// hexahedra with their displacement and Jacobians, 8.1 MB of arrays; zlib from Python on
/// 64 KiB blocks) level 1 leaves 55.2 % of the bytes in 0.17 s, level 6 54.4 % in 0.32 s; the
/// VTU goes from 10.8 MB to 5.9 MB.
const ZLIB_LEVEL: u32 = 1;

/// One `DataArray` in VTK's inline binary encoding with zlib compression (the file's
/// [`VTK_FILE_ATTRIBUTES`]): base64 of the header (UInt64 block count, block size, size of the
/// last block when partial, then each block's compressed size), followed by base64 of the
/// compressed blocks, as VTK writes it.
pub(crate) fn binary_array(
    s: &mut String,
    vtk_type: &str,
    name: Option<&str>,
    components: usize,
    bytes: &[u8],
) {
    use base64::Engine as _;
    use std::io::Write as _;
    let blocks: Vec<Vec<u8>> = bytes
        .chunks(BLOCK_BYTES)
        .map(|chunk| {
            let mut z = flate2::write::ZlibEncoder::new(
                Vec::with_capacity(chunk.len() / 2 + 64),
                flate2::Compression::new(ZLIB_LEVEL),
            );
            // (writing to a Vec cannot fail)
            let _ = z.write_all(chunk);
            z.finish().unwrap_or_default()
        })
        .collect();
    let mut header: Vec<u8> = Vec::with_capacity(8 * (3 + blocks.len()));
    for word in [blocks.len(), BLOCK_BYTES, bytes.len() % BLOCK_BYTES]
        .into_iter()
        .chain(blocks.iter().map(Vec::len))
    {
        header.extend_from_slice(&(word as u64).to_le_bytes());
    }
    let name = name.map(|n| format!(" Name=\"{n}\"")).unwrap_or_default();
    let comps = if components > 1 {
        format!(" NumberOfComponents=\"{components}\"")
    } else {
        String::new()
    };
    let b64 = &base64::engine::general_purpose::STANDARD;
    let _ = writeln!(
        s,
        "        <DataArray type=\"{vtk_type}\"{name}{comps} format=\"binary\">\n          {}{}\n        </DataArray>",
        b64.encode(&header),
        b64.encode(blocks.concat())
    );
}

pub(crate) fn f64_bytes(v: impl IntoIterator<Item = f64>) -> Vec<u8> {
    v.into_iter().flat_map(|x| x.to_le_bytes()).collect()
}

pub(crate) fn i64_bytes(v: impl IntoIterator<Item = usize>) -> Vec<u8> {
    v.into_iter()
        .flat_map(|x| (x as i64).to_le_bytes())
        .collect()
}

/// One set as a 0/1 mask array named `set_NAME`.
pub(crate) fn set_mask(s: &mut String, name: &str, members: &[usize], n: usize) {
    let mut mask = vec![0u8; n];
    for &m in members {
        if m < n {
            mask[m] = 1;
        }
    }
    binary_array(s, "UInt8", Some(&format!("set_{name}")), 1, &mask);
}

/// Writes an FE mesh as VTU (VTK XML, zlib-compressed binary arrays; readable by ParaView, VTK
/// and meshio), with cell data `jacobian_min` and `scaled_jacobian_min` (corner minima,
/// section 5.3), and, when `reference` is given (the same mesh before morphing), point data
/// `displacement` (node position minus reference). Node sets and element sets are point and cell data `set_NAME`
/// (1 for members, else 0); surfaces are not written (VTU has no face sets; use `.inp`,
/// `.msh` or `.feb`).
pub fn write_vtu<const D: usize>(
    path: &Path,
    mesh: &FeMesh<D>,
    reference: Option<&FeMesh<D>>,
) -> Result<()> {
    write_vtu_with_quality(path, mesh, reference, &mesh_quality(mesh))
}

/// [`write_vtu`] with the corner Jacobians already at hand (one per element).
pub fn write_vtu_with_quality<const D: usize>(
    path: &Path,
    mesh: &FeMesh<D>,
    reference: Option<&FeMesh<D>>,
    q: &[crate::mesh::quality::ElementQuality],
) -> Result<()> {
    write_vtu_with_point_data(path, mesh, reference, q, &[])
}

/// [`write_vtu_with_quality`] with named scalar point data (`(name, one value per node)`;
/// names of ASCII letters, digits and `_`).
///
/// # Errors
/// [`Error::Parameter`] for a field of another length than the nodes or an unusable name;
/// the errors of the write.
pub fn write_vtu_with_point_data<const D: usize>(
    path: &Path,
    mesh: &FeMesh<D>,
    reference: Option<&FeMesh<D>>,
    q: &[crate::mesh::quality::ElementQuality],
    fields: &[(&str, &[f64])],
) -> Result<()> {
    write_vtu_with_data(path, mesh, reference, q, fields, &[])
}

/// [`write_vtu_with_point_data`] with named scalar cell data too (`(name, one value per
/// element)`).
///
/// # Errors
/// As [`write_vtu_with_point_data`], for both kinds of field.
pub fn write_vtu_with_data<const D: usize>(
    path: &Path,
    mesh: &FeMesh<D>,
    reference: Option<&FeMesh<D>>,
    q: &[crate::mesh::quality::ElementQuality],
    fields: &[(&str, &[f64])],
    cell_fields: &[(&str, &[f64])],
) -> Result<()> {
    check_fields(path, fields, mesh.nodes.len())?;
    check_fields(path, cell_fields, mesh.num_elements())?;
    let k = mesh.kind.nodes();
    let ne = mesh.num_elements();
    let z = |p: &Point<D>| if D > 2 { p[2] } else { 0.0 };
    let mut s = String::with_capacity(mesh.nodes.len() * 40 + ne * 100);
    let _ = writeln!(
        s,
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" {VTK_FILE_ATTRIBUTES}>\n  <UnstructuredGrid>"
    );
    let _ = writeln!(
        s,
        "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">",
        mesh.nodes.len(),
        ne
    );
    s.push_str("      <PointData>\n");
    for (name, members) in &mesh.sets.node_sets {
        set_mask(&mut s, name, members, mesh.nodes.len());
    }
    if let Some(r) = reference {
        let d = mesh
            .nodes
            .iter()
            .zip(&r.nodes)
            .flat_map(|(p, o)| [p[0] - o[0], p[1] - o[1], z(p) - z(o)]);
        binary_array(&mut s, "Float64", Some("displacement"), 3, &f64_bytes(d));
    }
    scalar_arrays(&mut s, fields);
    s.push_str("      </PointData>\n      <CellData Scalars=\"scaled_jacobian_min\">\n");
    for (name, members) in &mesh.sets.element_sets {
        set_mask(&mut s, name, members, ne);
    }
    if q.len() == ne {
        let j = f64_bytes(q.iter().map(|e| e.jacobian_min));
        binary_array(&mut s, "Float64", Some("jacobian_min"), 1, &j);
        let sj = f64_bytes(q.iter().map(|e| e.scaled_jacobian_min));
        binary_array(&mut s, "Float64", Some("scaled_jacobian_min"), 1, &sj);
    }
    scalar_arrays(&mut s, cell_fields);
    s.push_str("      </CellData>\n      <Points>\n");
    let pts = f64_bytes(mesh.nodes.iter().flat_map(|p| [p[0], p[1], z(p)]));
    binary_array(&mut s, "Float64", None, 3, &pts);
    s.push_str("      </Points>\n      <Cells>\n");
    binary_array(
        &mut s,
        "Int64",
        Some("connectivity"),
        1,
        &i64_bytes(mesh.connectivity.iter().copied()),
    );
    binary_array(
        &mut s,
        "Int64",
        Some("offsets"),
        1,
        &i64_bytes((1..=ne).map(|e| e * k)),
    );
    binary_array(
        &mut s,
        "UInt8",
        Some("types"),
        1,
        &vec![mesh.kind.vtk_type(); ne],
    );
    s.push_str("      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n");
    crate::formats::write_atomic(path, s.as_bytes())
}

/// One Float64 `DataArray` per field (`(name, values)`).
fn scalar_arrays(s: &mut String, fields: &[(&str, &[f64])]) {
    for (name, values) in fields {
        binary_array(
            s,
            "Float64",
            Some(name),
            1,
            &f64_bytes(values.iter().copied()),
        );
    }
}

/// Refuses point data of another length than `n` or with a name that is not plain.
fn check_fields(path: &Path, fields: &[(&str, &[f64])], n: usize) -> Result<()> {
    for (name, values) in fields {
        if values.len() != n
            || name.is_empty()
            || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
        {
            return Err(Error::Parameter(format!(
                "{}: point data {name:?} of {} values for {n} points",
                path.display(),
                values.len()
            )));
        }
    }
    Ok(())
}

/// Writes a shape as VTP (zlib-compressed binary arrays): an outline as line cells, a surface
/// as polygons.
pub fn write_vtp<const D: usize>(path: &Path, shape: &Shape<D>) -> Result<()> {
    write_vtp_with_point_data(path, shape, &[])
}

/// [`write_vtp`] with named scalar point data (`(name, one value per point)`).
///
/// # Errors
/// As [`write_vtu_with_point_data`].
pub fn write_vtp_with_point_data<const D: usize>(
    path: &Path,
    shape: &Shape<D>,
    fields: &[(&str, &[f64])],
) -> Result<()> {
    check_fields(path, fields, shape.points.len())?;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" {VTK_FILE_ATTRIBUTES}>\n  <PolyData>"
    );
    let tag = if D == 2 { "Lines" } else { "Polys" };
    let (nl, np) = if D == 2 {
        (shape.facets.len(), 0)
    } else {
        (0, shape.facets.len())
    };
    let _ = writeln!(
        s,
        "    <Piece NumberOfPoints=\"{}\" NumberOfVerts=\"0\" NumberOfLines=\"{nl}\" NumberOfStrips=\"0\" NumberOfPolys=\"{np}\">",
        shape.points.len()
    );
    if !fields.is_empty() {
        s.push_str("      <PointData>\n");
        scalar_arrays(&mut s, fields);
        s.push_str("      </PointData>\n");
    }
    s.push_str("      <Points>\n");
    let z = |p: &Point<D>| if D > 2 { p[2] } else { 0.0 };
    let pts = f64_bytes(shape.points.iter().flat_map(|p| [p[0], p[1], z(p)]));
    binary_array(&mut s, "Float64", None, 3, &pts);
    let _ = writeln!(s, "      </Points>\n      <{tag}>");
    let conn = i64_bytes(shape.facets.iter().flat_map(|f| f.iter().copied()));
    binary_array(&mut s, "Int64", Some("connectivity"), 1, &conn);
    let offsets = i64_bytes((1..=shape.facets.len()).map(|i| i * D));
    binary_array(&mut s, "Int64", Some("offsets"), 1, &offsets);
    let _ = writeln!(s, "      </{tag}>\n    </Piece>\n  </PolyData>\n</VTKFile>");
    crate::formats::write_atomic(path, s.as_bytes())
}
