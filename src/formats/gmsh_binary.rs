//! Gmsh `.msh` binary files, 2.2 and 4.1 (`gmsh -bin`, meshio's default): the `$MeshFormat`
//! line says binary, a data size, and an integer 1 whose bytes give the byte order. Sections
//! are read in order; `$PhysicalNames` is text in binary files too; sections the mesh does not
//! need (`$NodeData`, `$Periodic`, ...) are read past.

use super::gmsh_parsed::{Parsed, gmsh_dimension, gmsh_nodes, physical_names};
use crate::error::{Error, Result};
use std::collections::HashMap;
use std::path::Path;

/// The `$MeshFormat` of a `.msh` file.
pub(crate) struct MshFormat {
    /// `2.2`, `4.1`...
    pub version: String,
    pub binary: bool,
    /// `size_t` width of 4.1 binary files.
    size_t: usize,
    /// Where the sections after `$EndMeshFormat` begin.
    after: usize,
    big_endian: bool,
}

/// Reads the `$MeshFormat` section (and, in binary files, the byte order).
pub(crate) fn mesh_format(path: &Path, bytes: &[u8]) -> Result<MshFormat> {
    let start = find(bytes, b"$MeshFormat", 0)
        .ok_or_else(|| Error::parse(path, 1, "no $MeshFormat section: not a Gmsh mesh"))?;
    let mut c = Cursor::new(path, bytes, start);
    c.line()?;
    let head = c.line()?;
    let f: Vec<&str> = head.split_whitespace().collect();
    let version = f.first().copied().unwrap_or("").to_string();
    let binary = f.get(1) == Some(&"1");
    let size_t = f.get(2).and_then(|s| s.parse().ok()).unwrap_or(8);
    if binary && size_t != 8 && size_t != 4 {
        return Err(Error::parse(
            path,
            2,
            format!("data size {size_t}: 4 or 8 is read"),
        ));
    }
    let mut big_endian = false;
    if binary {
        let one = c.take(4)?;
        big_endian = match one {
            [1, 0, 0, 0] => false,
            [0, 0, 0, 1] => true,
            _ => return Err(Error::parse(path, 3, "the binary byte-order word is not 1")),
        };
    }
    let end = find(bytes, b"$EndMeshFormat", c.pos)
        .ok_or_else(|| Error::parse(path, 0, "$MeshFormat is not closed (truncated?)"))?;
    Ok(MshFormat {
        version,
        binary,
        size_t,
        after: end + b"$EndMeshFormat".len(),
        big_endian,
    })
}

struct Cursor<'a> {
    path: &'a Path,
    b: &'a [u8],
    pos: usize,
    big_endian: bool,
    size_t: usize,
}

impl<'a> Cursor<'a> {
    fn new(path: &'a Path, b: &'a [u8], pos: usize) -> Self {
        Cursor {
            path,
            b,
            pos,
            big_endian: false,
            size_t: 8,
        }
    }
    fn err(&self, m: impl Into<String>) -> Error {
        Error::parse(self.path, 0, format!("at byte {}: {}", self.pos, m.into()))
    }
    /// The next text line (trimmed; empty lines skipped).
    fn line(&mut self) -> Result<&'a str> {
        loop {
            if self.pos >= self.b.len() {
                return Err(self.err("the file ends early (truncated?)"));
            }
            let end = self.b[self.pos..]
                .iter()
                .position(|&c| c == b'\n')
                .map_or(self.b.len(), |k| self.pos + k);
            let l = std::str::from_utf8(&self.b[self.pos..end])
                .map_err(|_| self.err("binary bytes where a text line was expected"))?
                .trim();
            self.pos = (end + 1).min(self.b.len());
            if !l.is_empty() {
                return Ok(l);
            }
        }
    }
    fn take(&mut self, n: usize) -> Result<&'a [u8]> {
        let s = self
            .b
            .get(self.pos..self.pos.saturating_add(n))
            .ok_or_else(|| self.err("the file ends inside a binary block (truncated?)"))?;
        self.pos += n;
        Ok(s)
    }
    fn word(&mut self, n: usize) -> Result<u64> {
        let c = self.take(n)?;
        let mut w = [0u8; 8];
        if self.big_endian {
            w[8 - n..].copy_from_slice(c);
            w.reverse();
        } else {
            w[..n].copy_from_slice(c);
        }
        Ok(u64::from_le_bytes(w))
    }
    fn int(&mut self) -> Result<i64> {
        Ok(self.word(4)? as u32 as i32 as i64)
    }
    fn size(&mut self) -> Result<usize> {
        let n = self.word(self.size_t)?;
        usize::try_from(n)
            .ok()
            .filter(|&n| n <= super::MAX_COUNT)
            .ok_or_else(|| self.err(format!("count {n} is out of range")))
    }
    fn tag(&mut self) -> Result<i64> {
        let n = self.word(self.size_t)?;
        i64::try_from(n).map_err(|_| self.err(format!("tag {n} is out of range")))
    }
    fn double(&mut self) -> Result<f64> {
        Ok(f64::from_bits(self.word(8)?))
    }
    /// Expects `$End{name}` next (after the newline that ends a binary block).
    fn end(&mut self, name: &str) -> Result<()> {
        let l = self.line()?;
        if l != format!("$End{name}") {
            return Err(self.err(format!(
                "${name} does not end with $End{name} (a count or size does not match the data)"
            )));
        }
        Ok(())
    }
}

/// Parses the sections of a binary `.msh` file.
pub(crate) fn parse(path: &Path, bytes: &[u8], f: &MshFormat) -> Result<Parsed> {
    let v4 = f.version.starts_with("4.1");
    if !v4 && !f.version.starts_with('2') {
        return Err(Error::parse(
            path,
            2,
            format!("Gmsh format version {}; 2.2 and 4.1 are read", f.version),
        ));
    }
    let mut c = Cursor::new(path, bytes, f.after);
    c.big_endian = f.big_endian;
    c.size_t = f.size_t;
    let mut out = Parsed::default();
    let mut phys_of: HashMap<(usize, i64), Vec<i64>> = HashMap::new();
    let (mut have_nodes, mut have_elements) = (false, false);
    while c.pos < bytes.len() {
        let l = match c.line() {
            Ok(l) => l,
            Err(_) if c.pos >= bytes.len() => break,
            Err(e) => return Err(e),
        };
        let Some(name) = l.strip_prefix('$') else {
            return Err(c.err(format!("{l:?} where a section ($Name) was expected")));
        };
        let name = name.to_string();
        match name.as_str() {
            "PhysicalNames" => {
                let n: usize = c
                    .line()?
                    .parse()
                    .map_err(|_| c.err("a bad $PhysicalNames count"))?;
                let mut lines = vec![""];
                for _ in 0..n.min(super::MAX_COUNT) {
                    lines.push(c.line()?);
                }
                out.names = physical_names(path, 0, &lines)?;
                c.end(&name)?;
            }
            "Entities" if v4 => {
                entities(&mut c, &mut phys_of)?;
                c.end(&name)?;
            }
            "Nodes" => {
                if v4 {
                    nodes_v4(&mut c, &mut out)?;
                } else {
                    nodes_v2(&mut c, &mut out)?;
                }
                c.end(&name)?;
                have_nodes = true;
            }
            "Elements" => {
                if v4 {
                    elements_v4(&mut c, &mut out, &phys_of)?;
                } else {
                    elements_v2(&mut c, &mut out)?;
                }
                c.end(&name)?;
                have_elements = true;
            }
            _ => {
                let end = format!("$End{name}");
                let at = find(bytes, end.as_bytes(), c.pos)
                    .ok_or_else(|| c.err(format!("${name} is not closed by {end} (truncated?)")))?;
                c.pos = at + end.len();
            }
        }
    }
    if !have_nodes {
        return Err(Error::parse(path, 0, "no $Nodes section"));
    }
    if !have_elements {
        return Err(Error::parse(path, 0, "no $Elements section"));
    }
    Ok(out)
}

/// 4.1 `$Entities`: the physical tags of each (dimension, entity).
fn entities(c: &mut Cursor, phys_of: &mut HashMap<(usize, i64), Vec<i64>>) -> Result<()> {
    let counts = [c.size()?, c.size()?, c.size()?, c.size()?];
    for (dim, &n) in counts.iter().enumerate() {
        for _ in 0..n {
            let tag = c.int()?;
            c.take(if dim == 0 { 24 } else { 48 })?;
            let np = c.size()?;
            let tags = (0..np).map(|_| c.int()).collect::<Result<Vec<_>>>()?;
            if dim > 0 {
                let nb = c.size()?;
                c.take(nb.saturating_mul(4))?;
            }
            phys_of.insert((dim, tag), tags);
        }
    }
    Ok(())
}

fn push_node(out: &mut Parsed, tag: i64, p: [f64; 3]) {
    out.node_index.insert(tag, out.nodes.len());
    out.nodes.push(p);
}

fn nodes_v2(c: &mut Cursor, out: &mut Parsed) -> Result<()> {
    let n: usize = c
        .line()?
        .parse()
        .ok()
        .filter(|&n| n <= super::MAX_COUNT)
        .ok_or_else(|| c.err("a bad node count"))?;
    if c.b.len().saturating_sub(c.pos) < n.saturating_mul(28) {
        return Err(c.err(format!(
            "{n} nodes announced; the file ends before (truncated?)"
        )));
    }
    for _ in 0..n {
        let tag = c.int()?;
        let p = [c.double()?, c.double()?, c.double()?];
        push_node(out, tag, p);
    }
    Ok(())
}

fn nodes_v4(c: &mut Cursor, out: &mut Parsed) -> Result<()> {
    let blocks = c.size()?;
    let _total = c.size()?;
    c.size()?;
    c.size()?;
    for _ in 0..blocks {
        let _dim = c.int()?;
        let _entity = c.int()?;
        let parametric = c.int()?;
        if parametric != 0 {
            return Err(c.err("parametric nodes are not read"));
        }
        let n = c.size()?;
        if c.b.len().saturating_sub(c.pos) < n.saturating_mul(c.size_t + 24) {
            return Err(c.err(format!(
                "a block of {n} nodes; the file ends before (truncated?)"
            )));
        }
        let tags = (0..n).map(|_| c.tag()).collect::<Result<Vec<_>>>()?;
        for tag in tags {
            let p = [c.double()?, c.double()?, c.double()?];
            push_node(out, tag, p);
        }
    }
    Ok(())
}

fn node_count(c: &Cursor, t: u32) -> Result<usize> {
    gmsh_nodes(t).ok_or_else(|| {
        c.err(format!(
            "element type {t}: its node count is not known here; save the mesh as ASCII or with the elements meshed"
        ))
    })
}

fn elements_v2(c: &mut Cursor, out: &mut Parsed) -> Result<()> {
    let n: usize = c
        .line()?
        .parse()
        .ok()
        .filter(|&n| n <= super::MAX_COUNT)
        .ok_or_else(|| c.err("a bad element count"))?;
    let mut read = 0;
    while read < n {
        let t = c.int()? as u32;
        let follow = usize::try_from(c.int()?).map_err(|_| c.err("a negative element count"))?;
        let ntags = usize::try_from(c.int()?).map_err(|_| c.err("a negative tag count"))?;
        if follow == 0 || follow > n - read || ntags > 64 {
            return Err(c.err("a bad element block header"));
        }
        let k = node_count(c, t)?;
        for _ in 0..follow {
            let tag = c.int()?;
            let tags = (0..ntags).map(|_| c.int()).collect::<Result<Vec<_>>>()?;
            let nodes = (0..k).map(|_| c.int()).collect::<Result<Vec<_>>>()?;
            if let Some(dim) = gmsh_dimension(t) {
                let phys = tags.first().map(|&p| vec![p]).unwrap_or_default();
                out.elements.push((dim, t, nodes, phys, tag));
            }
        }
        read += follow;
    }
    Ok(())
}

fn elements_v4(
    c: &mut Cursor,
    out: &mut Parsed,
    phys_of: &HashMap<(usize, i64), Vec<i64>>,
) -> Result<()> {
    let blocks = c.size()?;
    let _total = c.size()?;
    c.size()?;
    c.size()?;
    for _ in 0..blocks {
        let dim = usize::try_from(c.int()?).map_err(|_| c.err("a negative dimension"))?;
        let entity = c.int()?;
        let t = c.int()? as u32;
        let n = c.size()?;
        let k = node_count(c, t)?;
        if c.b.len().saturating_sub(c.pos) < n.saturating_mul((k + 1) * c.size_t) {
            return Err(c.err(format!(
                "a block of {n} elements; the file ends before (truncated?)"
            )));
        }
        let phys = phys_of.get(&(dim, entity)).cloned().unwrap_or_default();
        for _ in 0..n {
            let tag = c.tag()?;
            let nodes = (0..k).map(|_| c.tag()).collect::<Result<Vec<_>>>()?;
            out.elements.push((dim, t, nodes, phys.clone(), tag));
        }
    }
    Ok(())
}

fn find(hay: &[u8], needle: &[u8], from: usize) -> Option<usize> {
    hay.get(from..)?
        .windows(needle.len())
        .position(|w| w == needle)
        .map(|p| p + from)
}
