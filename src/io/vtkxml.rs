//! VTK XML files in: PolyData (`.vtp`, triangle surfaces) and UnstructuredGrid (`.vtu`,
//! hexahedral template meshes), with ASCII data arrays (as atlasmesh, ParaView's "ASCII"
//! option and meshio write them). Binary or appended arrays get a clear error.

use crate::error::{Error, Result};
use crate::fe::{ElementKind, FeMesh};
use crate::geometry::Point;
use std::path::Path;

/// The numbers of the first `DataArray` inside `<section>` (named `name` when given).
fn array(path: &Path, text: &str, section: &str, name: Option<&str>) -> Result<Vec<f64>> {
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
fn binary_values(
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

fn points(path: &Path, text: &str) -> Result<Vec<Point<3>>> {
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

fn index(path: &Path, v: f64, n: usize, what: &str) -> Result<usize> {
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
    if !text.contains("type=\"PolyData\"") {
        return Err(Error::parse(path, 1, "not a VTK XML PolyData file"));
    }
    let pts = points(path, &text)?;
    // Surfaces have Polys; outlines (as atlasmesh writes them) Lines.
    let cells = if text.contains("<Polys") {
        "Polys"
    } else {
        "Lines"
    };
    let conn = array(path, &text, cells, Some("connectivity"))?;
    let offs = array(path, &text, cells, Some("offsets"))?;
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
/// order). Point and cell data `set_NAME` (0/1, as [`crate::export::write_vtu`] writes them)
/// are read back as node and element sets.
pub fn read_vtu(path: &Path) -> Result<FeMesh<3>> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    if !text.contains("type=\"UnstructuredGrid\"") {
        return Err(Error::parse(path, 1, "not a VTK XML UnstructuredGrid file"));
    }
    let nodes = points(path, &text)?;
    let conn = array(path, &text, "Cells", Some("connectivity"))?;
    let offs = array(path, &text, "Cells", Some("offsets"))?;
    let types = array(path, &text, "Cells", Some("types"))?;
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
    let mut sets = crate::fe::MeshSets::default();
    for (section, n, target) in [
        ("PointData", nodes.len(), 0),
        ("CellData", connectivity.len() / k, 1),
    ] {
        let Some(body) = section_body(&text, section) else {
            continue;
        };
        for name in set_array_names(body) {
            let v = array(path, &text, section, Some(&format!("set_{name}")))?;
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
fn section_body<'a>(text: &'a str, section: &str) -> Option<&'a str> {
    let a = text.find(&format!("<{section}"))?;
    let b = text[a..].find(&format!("</{section}>"))? + a;
    Some(&text[a..b])
}

/// Names `X` of the `DataArray`s named `set_X` in `body`.
fn set_array_names(body: &str) -> Vec<String> {
    body.match_indices("Name=\"set_")
        .filter_map(|(i, m)| {
            let rest = &body[i + m.len()..];
            rest.find('"').map(|j| rest[..j].to_string())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Shape;

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
        crate::export::write_vtp(&p, &s).unwrap();
        let (pts, polys) = read_vtp(&p).unwrap();
        assert_eq!(pts, s.points);
        assert_eq!(
            polys,
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
        crate::export::write_vtu(&p, &cube, None).unwrap();
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
}
