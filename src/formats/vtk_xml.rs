//! VTK XML: VTP (polydata: outlines and surfaces) and VTU (unstructured grids: FE meshes with
//! their sets and quality) read and written.

use crate::error::{Error, Result};
use crate::geometry::{Point, Shape};
use crate::mesh::quality::mesh_quality;
use crate::mesh::{ElementKind, FeMesh};
use std::fmt::Write as _;
use std::path::Path;

/// The numbers of the first `DataArray` inside `<section>` (named `name` when given).
pub(crate) fn array(
    path: &Path,
    text: &str,
    section: &str,
    name: Option<&str>,
) -> Result<Vec<f64>> {
    let open = format!("<{section}");
    let start = text
        .find(&open)
        .ok_or_else(|| Error::parse(path, 0, format!("no <{section}> section")))?;
    let end = text[start..]
        .find(&format!("</{section}>"))
        .map(|e| start + e)
        .ok_or_else(|| Error::parse(path, 0, format!("<{section}> is not closed (truncated?)")))?;
    let body = &text[start..end];
    let mut at = 0;
    while let Some(p) = body[at..].find("<DataArray") {
        let tag_start = at + p;
        let tag_end = body[tag_start..]
            .find('>')
            .map(|e| tag_start + e)
            .ok_or_else(|| Error::parse(path, 0, "a <DataArray> tag is not closed"))?;
        let tag = &body[tag_start..tag_end];
        let close = body[tag_end..]
            .find("</DataArray>")
            .map(|e| tag_end + e)
            .ok_or_else(|| Error::parse(path, 0, "a <DataArray> is not closed (truncated?)"))?;
        at = close;
        if let Some(n) = name
            && !tag.contains(&format!("Name=\"{n}\""))
        {
            continue;
        }
        if tag.contains("format=\"binary\"") {
            return binary_values(path, text, section, tag, &body[tag_end + 1..close]);
        }
        if !tag.contains("format=\"ascii\"") {
            return Err(Error::parse(
                path,
                0,
                format!(
                    "the {section} data are appended; ASCII and inline binary VTK XML are read"
                ),
            ));
        }
        return body[tag_end + 1..close]
            .split_whitespace()
            .map(|t| {
                t.parse::<f64>().map_err(|_| {
                    Error::parse(path, 0, format!("'{t}' in <{section}> is not a number"))
                })
            })
            .collect();
    }
    Err(Error::parse(
        path,
        0,
        format!(
            "no DataArray{} in <{section}>",
            name.map(|n| format!(" '{n}'")).unwrap_or_default()
        ),
    ))
}

/// The values of an inline binary `DataArray` (base64 of a byte-count header, `UInt32` or
/// `UInt64` per the file's `header_type`, then the little-endian values; uncompressed).
pub(crate) fn binary_values(
    path: &Path,
    text: &str,
    section: &str,
    tag: &str,
    content: &str,
) -> Result<Vec<f64>> {
    use base64::Engine as _;
    let bad = |m: String| Error::parse(path, 0, format!("<{section}>: {m}"));
    if text.contains("compressor=") {
        return Err(bad("compressed data are not read; save uncompressed".into()));
    }
    if text.contains("byte_order=\"BigEndian\"") {
        return Err(bad("big-endian binary data are not read".into()));
    }
    let clean: String = content.chars().filter(|c| !c.is_whitespace()).collect();
    let raw = base64::engine::general_purpose::STANDARD
        .decode(clean.as_bytes())
        .map_err(|e| bad(format!("bad base64 ({e})")))?;
    let header = if text.contains("header_type=\"UInt64\"") {
        8
    } else {
        4
    };
    if raw.len() < header {
        return Err(bad("a binary array is truncated".into()));
    }
    let n = if header == 8 {
        u64::from_le_bytes(raw[..8].try_into().unwrap_or([0; 8])) as usize
    } else {
        u32::from_le_bytes(raw[..4].try_into().unwrap_or([0; 4])) as usize
    };
    let data = raw.get(header..header.saturating_add(n)).ok_or_else(|| {
        bad(format!(
            "a binary array announces {n} bytes but holds {}",
            raw.len() - header
        ))
    })?;
    let ty = tag
        .split("type=\"")
        .nth(1)
        .and_then(|t| t.split('"').next())
        .unwrap_or("");
    let width = match ty {
        "Float64" | "Int64" | "UInt64" => 8,
        "Float32" | "Int32" | "UInt32" => 4,
        "Int16" | "UInt16" => 2,
        "Int8" | "UInt8" => 1,
        _ => return Err(bad(format!("data type {ty:?} is not read"))),
    };
    if data.len() % width != 0 {
        return Err(bad(
            "a binary array's size is not a whole number of values".into()
        ));
    }
    Ok(data
        .chunks_exact(width)
        .map(|c| match ty {
            "Float64" => f64::from_le_bytes(c.try_into().unwrap_or([0; 8])),
            "Int64" => i64::from_le_bytes(c.try_into().unwrap_or([0; 8])) as f64,
            "UInt64" => u64::from_le_bytes(c.try_into().unwrap_or([0; 8])) as f64,
            "Float32" => f32::from_le_bytes(c.try_into().unwrap_or([0; 4])) as f64,
            "Int32" => i32::from_le_bytes(c.try_into().unwrap_or([0; 4])) as f64,
            "UInt32" => u32::from_le_bytes(c.try_into().unwrap_or([0; 4])) as f64,
            "Int16" => i16::from_le_bytes(c.try_into().unwrap_or([0; 2])) as f64,
            "UInt16" => u16::from_le_bytes(c.try_into().unwrap_or([0; 2])) as f64,
            "Int8" => c[0] as i8 as f64,
            _ => c[0] as f64,
        })
        .collect())
}

pub(crate) fn points(path: &Path, text: &str) -> Result<Vec<Point<3>>> {
    let v = array(path, text, "Points", None)?;
    if v.len() % 3 != 0 {
        return Err(Error::parse(
            path,
            0,
            "the point coordinates are not triples",
        ));
    }
    Ok(v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
}

pub(crate) fn index(path: &Path, v: f64, n: usize, what: &str) -> Result<usize> {
    if v >= 0.0 && v.fract() == 0.0 && (v as usize) < n {
        Ok(v as usize)
    } else {
        Err(Error::parse(
            path,
            0,
            format!("{what} {v} is out of range (0..{n})"),
        ))
    }
}

/// Reads the points and polygons (or, without polygons, the lines) of a VTK XML PolyData
/// file (ASCII arrays).
pub fn read_vtp(path: &Path) -> Result<(Vec<Point<3>>, Vec<Vec<usize>>)> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    parse_vtp(path, &text)
}

/// [`read_vtp`] of a file's text (`path` only names the file in messages): no file is read.
pub fn parse_vtp(path: &Path, text: &str) -> Result<(Vec<Point<3>>, Vec<Vec<usize>>)> {
    if !text.contains("type=\"PolyData\"") {
        return Err(Error::parse(path, 1, "not a VTK XML PolyData file"));
    }
    let pts = points(path, text)?;
    // Surfaces have Polys; outlines (as atlasmesh writes them) Lines.
    let cells = if text.contains("<Polys") {
        "Polys"
    } else {
        "Lines"
    };
    let conn = array(path, text, cells, Some("connectivity"))?;
    let offs = array(path, text, cells, Some("offsets"))?;
    let mut polys = Vec::with_capacity(offs.len());
    let mut prev = 0usize;
    for &o in &offs {
        let o = index(path, o, conn.len() + 1, "offset")?;
        if o < prev {
            return Err(Error::parse(path, 0, "the polygon offsets decrease"));
        }
        let poly = conn[prev..o]
            .iter()
            .map(|&v| index(path, v, pts.len(), "vertex index"))
            .collect::<Result<Vec<_>>>()?;
        polys.push(poly);
        prev = o;
    }
    Ok((pts, polys))
}

/// Reads an FE mesh from a VTK XML UnstructuredGrid file (ASCII arrays; one cell type of
/// VTK's 5, 9, 10 or 12: triangles, quadrilaterals, tetrahedra, hexahedra, in VTK's node
/// order). Point and cell data `set_NAME` (0/1, as [`crate::formats::write_vtu`] writes them)
/// are read back as node and element sets.
pub fn read_vtu(path: &Path) -> Result<FeMesh<3>> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    parse_vtu(path, &text)
}

/// [`read_vtu`] of a file's text (`path` only names the file in messages): no file is read.
pub fn parse_vtu(path: &Path, text: &str) -> Result<FeMesh<3>> {
    if !text.contains("type=\"UnstructuredGrid\"") {
        return Err(Error::parse(path, 1, "not a VTK XML UnstructuredGrid file"));
    }
    let nodes = points(path, text)?;
    let conn = array(path, text, "Cells", Some("connectivity"))?;
    let offs = array(path, text, "Cells", Some("offsets"))?;
    let types = array(path, text, "Cells", Some("types"))?;
    if types.len() != offs.len() {
        return Err(Error::parse(
            path,
            0,
            "cell types and offsets differ in number",
        ));
    }
    let kind = types
        .first()
        .and_then(|&t| ElementKind::from_vtk_type(t as u8))
        .ok_or_else(|| {
            Error::parse(
                path,
                0,
                format!(
                    "cell type {:?}: only triangles (5), quadrilaterals (9), tetrahedra (10) and hexahedra (12) are read",
                    types.first()
                ),
            )
        })?;
    let k = kind.nodes();
    let mut connectivity = Vec::with_capacity(conn.len());
    let mut prev = 0usize;
    for (e, (&o, &t)) in offs.iter().zip(&types).enumerate() {
        if t != kind.vtk_type() as f64 {
            return Err(Error::parse(
                path,
                0,
                format!(
                    "cell {e} has VTK type {t} but cell 0 has {}; one element type per mesh",
                    kind.vtk_type()
                ),
            ));
        }
        let o = index(path, o, conn.len() + 1, "offset")?;
        if o != prev + k {
            return Err(Error::parse(
                path,
                0,
                format!("cell {e} does not have {k} nodes"),
            ));
        }
        for &v in &conn[prev..o] {
            connectivity.push(index(path, v, nodes.len(), "node index")?);
        }
        prev = o;
    }
    if connectivity.is_empty() {
        return Err(Error::parse(path, 0, "the mesh has no cells"));
    }
    if nodes.iter().any(|p| p.iter().any(|c| !c.is_finite())) {
        return Err(Error::parse(
            path,
            0,
            "a node has a NaN or infinite coordinate",
        ));
    }
    let mut sets = crate::mesh::MeshSets::default();
    for (section, n, target) in [
        ("PointData", nodes.len(), 0),
        ("CellData", connectivity.len() / k, 1),
    ] {
        let Some(body) = section_body(text, section) else {
            continue;
        };
        for name in set_array_names(body) {
            let v = array(path, text, section, Some(&format!("set_{name}")))?;
            if v.len() != n {
                return Err(Error::parse(
                    path,
                    0,
                    format!("set_{name} has {} values, {n} expected", v.len()),
                ));
            }
            let members: Vec<usize> = (0..n).filter(|&i| v[i] != 0.0).collect();
            if target == 0 {
                sets.node_sets.insert(name, members);
            } else {
                sets.element_sets.insert(name, members);
            }
        }
    }
    Ok(FeMesh {
        nodes,
        kind,
        connectivity,
        sets,
    })
}

/// The text between `<section` and `</section>`.
pub(crate) fn section_body<'a>(text: &'a str, section: &str) -> Option<&'a str> {
    let a = text.find(&format!("<{section}"))?;
    let b = text[a..].find(&format!("</{section}>"))? + a;
    Some(&text[a..b])
}

/// Names `X` of the `DataArray`s named `set_X` in `body`.
pub(crate) fn set_array_names(body: &str) -> Vec<String> {
    body.match_indices("Name=\"set_")
        .filter_map(|(i, m)| {
            let rest = &body[i + m.len()..];
            rest.find('"').map(|j| rest[..j].to_string())
        })
        .collect()
}

pub(crate) fn points_xml<const D: usize>(out: &mut String, pts: &[Point<D>]) {
    out.push_str("      <Points>\n        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n");
    for p in pts {
        let z = if D > 2 { p[2] } else { 0.0 };
        let _ = writeln!(out, "          {:.17e} {:.17e} {:.17e}", p[0], p[1], z);
    }
    out.push_str("        </DataArray>\n      </Points>\n");
}

/// One `DataArray` in VTK's inline binary encoding: base64 of a UInt64 byte count followed by
/// the little-endian values (`header_type="UInt64"`, no compression).
pub(crate) fn binary_array(
    s: &mut String,
    vtk_type: &str,
    name: Option<&str>,
    components: usize,
    bytes: &[u8],
) {
    use base64::Engine as _;
    let mut raw = Vec::with_capacity(8 + bytes.len());
    raw.extend_from_slice(&(bytes.len() as u64).to_le_bytes());
    raw.extend_from_slice(bytes);
    let name = name.map(|n| format!(" Name=\"{n}\"")).unwrap_or_default();
    let comps = if components > 1 {
        format!(" NumberOfComponents=\"{components}\"")
    } else {
        String::new()
    };
    let _ = writeln!(
        s,
        "        <DataArray type=\"{vtk_type}\"{name}{comps} format=\"binary\">\n          {}\n        </DataArray>",
        base64::engine::general_purpose::STANDARD.encode(&raw)
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

/// Writes an FE mesh as VTU (VTK XML, binary arrays; readable by ParaView and meshio), with
/// cell data `jacobian_min` and `scaled_jacobian_min` (corner minima, section 5.3), and, when
/// `reference` is given (the same mesh before morphing), point data `displacement` (node
/// position minus reference). Node sets and element sets are point and cell data `set_NAME`
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
    let k = mesh.kind.nodes();
    let ne = mesh.num_elements();
    let z = |p: &Point<D>| if D > 2 { p[2] } else { 0.0 };
    let mut s = String::with_capacity(mesh.nodes.len() * 40 + ne * 100);
    s.push_str("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n  <UnstructuredGrid>\n");
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

/// Writes a shape as VTP: an outline as line cells, a surface as polygons.
pub fn write_vtp<const D: usize>(path: &Path, shape: &Shape<D>) -> Result<()> {
    let mut s = String::new();
    s.push_str("<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n  <PolyData>\n");
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
    points_xml(&mut s, &shape.points);
    let _ = writeln!(
        s,
        "      <{tag}>\n        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">"
    );
    for f in &shape.facets {
        let _ = writeln!(
            s,
            "          {}",
            f.iter()
                .map(|i| i.to_string())
                .collect::<Vec<_>>()
                .join(" ")
        );
    }
    s.push_str("        </DataArray>\n        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    for i in 0..shape.facets.len() {
        let _ = writeln!(s, "          {}", (i + 1) * D);
    }
    let _ = writeln!(
        s,
        "        </DataArray>\n      </{tag}>\n    </Piece>\n  </PolyData>\n</VTKFile>"
    );
    crate::formats::write_atomic(path, s.as_bytes())
}
