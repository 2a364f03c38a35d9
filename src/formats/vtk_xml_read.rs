//! The VTK XML document as VTK, ParaView, PyVista and meshio write it: pieces, their sections
//! (`Points`, `Polys`, `Cells`, `PointData`...) and their `DataArray`s, parsed with a real XML
//! parser. Arrays are decoded when asked for: inline ASCII or base64, appended raw or base64,
//! with a `UInt32` or `UInt64` byte-count header, little- or big-endian, uncompressed or
//! compressed by `vtkZLibDataCompressor` or `vtkLZ4DataCompressor` (LZMA is refused with what
//! to do). Child elements of a `DataArray` (VTK's `<InformationKey>`) are skipped.

use crate::error::{Error, Result};
use quick_xml::events::{BytesStart, Event};
use std::path::Path;

/// The largest decoded array, in bytes (a compressed header announcing more is refused).
const MAX_ARRAY_BYTES: usize = 8 * super::MAX_COUNT;

// What decoding one file may take, in bytes of decoded data and of the `f64` values made
// from it, all its arrays together: `decode_budget` of the file's size. A file that inflates
// beyond it is refused before the memory is taken (a decompression bomb, or many arrays
// sharing one appended block).
use super::input::{DECODE_FACTOR, decode_budget};

/// Where an array's values are.
enum Source {
    /// Inline text: ASCII numbers, or base64 (`format="binary"`).
    Inline { binary: bool, text: String },
    /// In the `<AppendedData>` block, at this offset.
    Appended(usize),
}

/// An array as stored: ASCII text, or binary values once decoded.
enum Stored<'s> {
    Text(&'s str),
    Binary(Vec<u8>),
}

/// One `DataArray`, not yet decoded.
pub(crate) struct ArraySpec {
    /// `Name` (empty when absent).
    pub name: String,
    /// `type` (`Float32`, `Int64`...).
    ty: String,
    source: Source,
}

/// One section of a piece (`Points`, `Polys`, `Cells`, `PointData`...).
pub(crate) struct Section {
    pub tag: String,
    pub arrays: Vec<ArraySpec>,
}

/// One `<Piece>`.
#[derive(Default)]
pub(crate) struct Piece {
    /// `NumberOfPoints`.
    pub points: usize,
    /// Its sections, in the file's order.
    pub sections: Vec<Section>,
}

impl Piece {
    /// The section `tag`, if the piece has it.
    pub fn section(&self, tag: &str) -> Option<&Section> {
        self.sections.iter().find(|s| s.tag == tag)
    }
}

#[derive(Clone, Copy, PartialEq)]
enum Compressor {
    None,
    Zlib,
    Lz4,
}

/// A parsed VTK XML file.
pub(crate) struct Document<'a> {
    path: &'a Path,
    /// `type` of `<VTKFile>` (`PolyData`, `UnstructuredGrid`).
    pub kind: String,
    pub pieces: Vec<Piece>,
    big_endian: bool,
    header64: bool,
    compressor: Compressor,
    /// The appended block after its `_`: raw bytes, or base64 text.
    appended: Option<(&'a [u8], bool)>,
    /// Bytes decoding may still take ([`decode_budget`]).
    budget: std::cell::Cell<usize>,
    /// The whole budget, for messages.
    budget_total: usize,
}

fn attr(e: &BytesStart, key: &str) -> Option<String> {
    e.attributes()
        .with_checks(false)
        .flatten()
        .find(|a| a.key.as_ref() == key)
        .map(|a| a.value.into_owned())
}

impl<'a> Document<'a> {
    /// The file, for messages.
    pub fn path(&self) -> &'a Path {
        self.path
    }

    /// Parses the XML part of `bytes` (everything before `<AppendedData>`, which may hold raw
    /// binary); `path` only names the file in messages.
    #[allow(
        clippy::too_many_lines,
        reason = "a parser: one walk over the XML events, each element's branch beside the others"
    )]
    pub fn parse(path: &'a Path, bytes: &'a [u8]) -> Result<Self> {
        let bad = |m: String| Error::parse(path, 0, m);
        let appended_at = find(bytes, b"<AppendedData");
        let head = &bytes[..appended_at.unwrap_or(bytes.len())];
        let text = std::str::from_utf8(head).map_err(|_| {
            bad("not a VTK XML file (invalid UTF-8 before any appended data)".into())
        })?;
        let mut r = quick_xml::Reader::from_str(text);
        r.config_mut().check_end_names = true;
        let mut doc = Document {
            path,
            kind: String::new(),
            pieces: Vec::new(),
            big_endian: false,
            header64: false,
            compressor: Compressor::None,
            appended: None,
            budget: std::cell::Cell::new(0),
            budget_total: decode_budget(bytes.len()),
        };
        doc.budget.set(doc.budget_total);
        let mut stack: Vec<String> = Vec::new();
        // The array being read and the depth of its element.
        let mut open: Option<(ArraySpec, usize)> = None;
        let mut root = false;
        loop {
            let ev = r.read_event().map_err(|e| {
                bad(format!(
                    "not well-formed XML near byte {} ({e})",
                    r.error_position()
                ))
            })?;
            match ev {
                Event::Start(ref e) | Event::Empty(ref e) => {
                    let empty = matches!(ev, Event::Empty(_));
                    let tag = e.local_name().as_ref().to_string();
                    if !root {
                        if tag != "VTKFile" {
                            return Err(bad(format!("not a VTK XML file (root <{tag}>)")));
                        }
                        root = true;
                        doc.kind = attr(e, "type").unwrap_or_default();
                        doc.big_endian = attr(e, "byte_order").as_deref() == Some("BigEndian");
                        doc.header64 = attr(e, "header_type").as_deref() == Some("UInt64");
                        doc.compressor = match attr(e, "compressor").as_deref() {
                            None | Some("") => Compressor::None,
                            Some("vtkZLibDataCompressor") => Compressor::Zlib,
                            Some("vtkLZ4DataCompressor") => Compressor::Lz4,
                            Some("vtkLZMADataCompressor") => {
                                return Err(bad("LZMA-compressed data are not read; save with zlib or LZ4 compression or none (ParaView: Compressor Type; PyVista: compression='zlib'; VTK: SetCompressorTypeToZLib)".into()));
                            }
                            Some(c) => return Err(bad(format!("compressor {c:?} is not read"))),
                        };
                    } else if open.is_none() && tag == "Piece" {
                        let points = attr(e, "NumberOfPoints")
                            .map(|n| {
                                n.trim()
                                    .parse::<usize>()
                                    .ok()
                                    .filter(|&n| n <= super::MAX_COUNT)
                                    .ok_or_else(|| bad(format!("NumberOfPoints {n:?}")))
                            })
                            .transpose()?
                            .unwrap_or(0);
                        doc.pieces.push(Piece {
                            points,
                            sections: Vec::new(),
                        });
                    } else if open.is_none() && tag == "DataArray" {
                        let source = match attr(e, "format").as_deref().unwrap_or("ascii") {
                            "appended" => {
                                let o = attr(e, "offset").unwrap_or_default();
                                Source::Appended(o.trim().parse().map_err(|_| {
                                    bad(format!("an appended DataArray has offset {o:?}"))
                                })?)
                            }
                            f => Source::Inline {
                                binary: f == "binary",
                                text: String::new(),
                            },
                        };
                        let spec = ArraySpec {
                            name: attr(e, "Name").unwrap_or_default(),
                            ty: attr(e, "type").unwrap_or_default(),
                            source,
                        };
                        if empty {
                            doc.push(&stack, spec);
                        } else {
                            open = Some((spec, stack.len() + 1));
                        }
                    }
                    if !empty {
                        stack.push(tag);
                    }
                }
                Event::End(_) => {
                    if let Some((_, depth)) = &open
                        && *depth == stack.len()
                        && let Some((spec, _)) = open.take()
                    {
                        stack.pop();
                        doc.push(&stack, spec);
                        continue;
                    }
                    stack.pop();
                }
                Event::Text(t) => {
                    if let Some((
                        ArraySpec {
                            source: Source::Inline { text, .. },
                            ..
                        },
                        depth,
                    )) = &mut open
                        && *depth == stack.len()
                    {
                        text.push_str(&t);
                    }
                }
                Event::Eof => break,
                _ => {}
            }
        }
        if !root {
            return Err(bad("not a VTK XML file (no <VTKFile>)".into()));
        }
        if open.is_some() {
            return Err(bad("a <DataArray> is not closed (truncated?)".into()));
        }
        if let Some(at) = appended_at {
            let rest = &bytes[at..];
            let close = rest
                .iter()
                .position(|&b| b == b'>')
                .ok_or_else(|| bad("the <AppendedData> tag is not closed (truncated?)".into()))?;
            let tag = String::from_utf8_lossy(&rest[..close]);
            let base64 = !tag.contains("\"raw\"");
            let us = rest[close..]
                .iter()
                .position(|&b| b == b'_')
                .map(|u| close + u + 1)
                .ok_or_else(|| bad("<AppendedData> has no '_' before its data".into()))?;
            let mut data = &rest[us..];
            if base64 && let Some(end) = rfind(data, b"</AppendedData>") {
                data = &data[..end];
            }
            doc.appended = Some((data, base64));
        } else if !stack.is_empty() {
            return Err(bad(format!(
                "<{}> is not closed (truncated?)",
                stack.last().map(String::as_str).unwrap_or("")
            )));
        }
        Ok(doc)
    }

    fn push(&mut self, stack: &[String], spec: ArraySpec) {
        let section = stack.last().cloned().unwrap_or_default();
        // Arrays outside a piece (FieldData of the dataset) are not needed.
        if let Some(p) = self.pieces.last_mut() {
            match p.sections.iter_mut().find(|s| s.tag == section) {
                Some(s) => s.arrays.push(spec),
                None => p.sections.push(Section {
                    tag: section,
                    arrays: vec![spec],
                }),
            }
        }
    }

    /// The width in bytes of one value of `a`'s type, or why it is not read.
    fn width(a: &ArraySpec) -> std::result::Result<usize, String> {
        Ok(match a.ty.as_str() {
            "Float64" | "Int64" | "UInt64" => 8,
            "Float32" | "Int32" | "UInt32" => 4,
            "Int16" | "UInt16" => 2,
            "Int8" | "UInt8" | "Char" => 1,
            t => return Err(format!("data type {t:?} is not read")),
        })
    }

    /// The error for array `a` of `section`.
    fn array_error(&self, a: &ArraySpec, section: &str, m: String) -> Error {
        Error::parse(
            self.path,
            0,
            format!(
                "<{section}> array{}: {m}",
                if a.name.is_empty() {
                    String::new()
                } else {
                    format!(" '{}'", a.name)
                }
            ),
        )
    }

    /// The stored form of `a`: its ASCII text, or its decoded binary bytes (each value
    /// `width` bytes, in the file's byte order).
    fn stored<'s>(
        &'s self,
        a: &'s ArraySpec,
        width: usize,
    ) -> std::result::Result<Stored<'s>, String> {
        let bytes = match &a.source {
            Source::Inline {
                binary: false,
                text,
            } => return Ok(Stored::Text(text)),
            Source::Inline { binary: true, text } => {
                self.payload(&base64_segments(text.as_bytes())?)?
            }
            Source::Appended(offset) => {
                let (data, base64) = self
                    .appended
                    .ok_or("appended data announced but no <AppendedData>")?;
                let from = data.get(*offset..).ok_or_else(|| {
                    format!("offset {offset} is past the appended data (truncated?)")
                })?;
                if base64 {
                    self.payload(&base64_segments(from)?)?
                } else {
                    self.payload(from)?
                }
            }
        };
        if !bytes.len().is_multiple_of(width) {
            return Err("its size is not a whole number of values".into());
        }
        Ok(Stored::Binary(bytes))
    }

    /// One binary value of `width` bytes in the file's byte order, as a little-endian word.
    fn word(&self, c: &[u8]) -> u64 {
        let mut w = [0u8; 8];
        if self.big_endian {
            w[8 - c.len()..].copy_from_slice(c);
            w.reverse();
        } else {
            w[..c.len()].copy_from_slice(c);
        }
        u64::from_le_bytes(w)
    }

    /// The values of `a`, as f64 (integers up to 2^53 exactly).
    pub fn values(&self, a: &ArraySpec, section: &str) -> Result<Vec<f64>> {
        let bad = |m: String| self.array_error(a, section, m);
        let width = Self::width(a).map_err(bad)?;
        let bytes = match self.stored(a, width).map_err(bad)? {
            Stored::Text(text) => {
                self.charge(text.len().saturating_mul(8) / 2).map_err(bad)?;
                return text
                    .split_whitespace()
                    .map(|t| {
                        t.parse::<f64>()
                            .map_err(|_| bad(format!("{t:?} is not a number")))
                    })
                    .collect();
            }
            Stored::Binary(b) => b,
        };
        self.charge(bytes.len() / width * 8).map_err(bad)?;
        Ok(bytes
            .chunks_exact(width)
            .map(|c| {
                let u = self.word(c);
                match a.ty.as_str() {
                    "Float64" => f64::from_bits(u),
                    "Float32" => f32::from_bits(u as u32) as f64,
                    "Int64" => u as i64 as f64,
                    "Int32" => u as u32 as i32 as f64,
                    "Int16" => u as u16 as i16 as f64,
                    "Int8" | "Char" => u as u8 as i8 as f64,
                    _ => u as f64,
                }
            })
            .collect())
    }

    /// The values of an integer array (cell connectivity, offsets, types) as integers, never
    /// through `f64`: every 64-bit value exact, an unsigned value beyond `i64::MAX` or a
    /// fractional value (an integer array written as floats) refused.
    pub fn integers(&self, a: &ArraySpec, section: &str) -> Result<Vec<i64>> {
        let bad = |m: String| self.array_error(a, section, m);
        let width = Self::width(a).map_err(bad)?;
        let bytes = match self.stored(a, width).map_err(bad)? {
            Stored::Text(text) => {
                self.charge(text.len().saturating_mul(8) / 2).map_err(bad)?;
                return text
                    .split_whitespace()
                    .map(|t| {
                        t.parse::<i64>()
                            .map_err(|_| bad(format!("{t:?} is not an integer")))
                    })
                    .collect();
            }
            Stored::Binary(b) => b,
        };
        self.charge(bytes.len() / width * 8).map_err(bad)?;
        let float = |v: f64| -> Result<i64> {
            if v.fract() == 0.0 && v.abs() < 9.0e18 {
                Ok(v as i64)
            } else {
                Err(bad(format!("{v} is not an integer")))
            }
        };
        bytes
            .chunks_exact(width)
            .map(|c| {
                let u = self.word(c);
                match a.ty.as_str() {
                    "Float64" => float(f64::from_bits(u)),
                    "Float32" => float(f32::from_bits(u as u32) as f64),
                    "Int64" => Ok(u as i64),
                    "Int32" => Ok(i64::from(u as u32 as i32)),
                    "Int16" => Ok(i64::from(u as u16 as i16)),
                    "Int8" | "Char" => Ok(i64::from(u as u8 as i8)),
                    _ => i64::try_from(u)
                        .map_err(|_| bad(format!("{u} is beyond the largest index"))),
                }
            })
            .collect()
    }

    /// Takes `n` bytes from the file's decoding budget, or says why not.
    fn charge(&self, n: usize) -> std::result::Result<(), String> {
        let left = self.budget.get();
        if n > left {
            return Err(format!(
                "decoding the file's arrays would take more than {} MB, {DECODE_FACTOR} times \
                 the file's size (a decompression bomb, or arrays sharing one block?)",
                self.budget_total >> 20
            ));
        }
        self.budget.set(left - n);
        Ok(())
    }

    /// The data bytes of one binary array from its encoded block (header, then the values,
    /// compressed in blocks when the file has a compressor). Only the bytes the header
    /// announces are read; a block may be followed by others (appended data).
    fn payload(&self, block: &[u8]) -> std::result::Result<Vec<u8>, String> {
        let hw = if self.header64 { 8 } else { 4 };
        let word = |i: usize| -> std::result::Result<usize, String> {
            let c = block
                .get(i * hw..(i + 1) * hw)
                .ok_or("the binary header is truncated")?;
            let mut w = [0u8; 8];
            if self.big_endian {
                w[8 - hw..].copy_from_slice(c);
                w.reverse();
            } else {
                w[..hw].copy_from_slice(c);
            }
            usize::try_from(u64::from_le_bytes(w)).map_err(|_| "a header count is too large".into())
        };
        if self.compressor == Compressor::None {
            let n = word(0)?;
            if n > MAX_ARRAY_BYTES {
                return Err(format!("an array of {n} bytes is beyond the limit"));
            }
            self.charge(n)?;
            return block.get(hw..hw + n).map(<[u8]>::to_vec).ok_or_else(|| {
                format!("the array announces {n} bytes but the file ends before (truncated?)")
            });
        }
        let (nb, bs, last) = (word(0)?, word(1)?, word(2)?);
        let total = if nb == 0 {
            Some(0)
        } else if last == 0 {
            nb.checked_mul(bs)
        } else {
            (nb - 1).checked_mul(bs).and_then(|t| t.checked_add(last))
        }
        .filter(|&t| t <= MAX_ARRAY_BYTES)
        .ok_or("the compressed array announces a size beyond the limit")?;
        // Charged before anything is inflated.
        self.charge(total)?;
        let mut out = Vec::with_capacity(total);
        let mut at = hw.checked_mul(3 + nb).ok_or("a bad block count")?;
        for b in 0..nb {
            let size = word(3 + b)?;
            let expect = if b + 1 == nb && last != 0 { last } else { bs };
            let data = block
                .get(at..at.saturating_add(size))
                .ok_or("a compressed block is truncated")?;
            at += size;
            match self.compressor {
                Compressor::Zlib => {
                    use std::io::Read as _;
                    let before = out.len();
                    flate2::read::ZlibDecoder::new(data)
                        .take(expect as u64)
                        .read_to_end(&mut out)
                        .map_err(|e| format!("a zlib block does not decompress ({e})"))?;
                    if out.len() - before != expect {
                        return Err("a zlib block is shorter than announced".into());
                    }
                }
                _ => {
                    let d = lz4_flex::block::decompress(data, expect)
                        .map_err(|e| format!("an LZ4 block does not decompress ({e})"))?;
                    if d.len() != expect {
                        return Err("an LZ4 block is shorter than announced".into());
                    }
                    out.extend_from_slice(&d);
                }
            }
        }
        Ok(out)
    }
}

/// Decodes base64 made of separately padded segments, as VTK writes a compressed array's
/// header and its data (whitespace ignored; decoding stops at the first character that is not
/// base64, where the next appended array begins).
fn base64_segments(text: &[u8]) -> std::result::Result<Vec<u8>, String> {
    use base64::Engine as _;
    let clean: Vec<u8> = text
        .iter()
        .copied()
        .filter(|c| !c.is_ascii_whitespace())
        .take_while(|&c| c.is_ascii_alphanumeric() || c == b'+' || c == b'/' || c == b'=')
        .collect();
    let mut out = Vec::with_capacity(clean.len() / 4 * 3);
    let mut start = 0;
    let mut i = 0;
    while i < clean.len() {
        // A segment ends after its padding, or at a 4-character boundary at the end.
        if clean[i] == b'=' {
            while i < clean.len() && clean[i] == b'=' {
                i += 1;
            }
            decode(&clean[start..i], &mut out)?;
            start = i;
        } else {
            i += 1;
        }
    }
    if start < clean.len() {
        decode(&clean[start..], &mut out)?;
    }
    return Ok(out);

    fn decode(seg: &[u8], out: &mut Vec<u8>) -> std::result::Result<(), String> {
        base64::engine::general_purpose::STANDARD
            .decode_vec(seg, out)
            .map_err(|e| format!("bad base64 ({e})"))
    }
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

fn rfind(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).rposition(|w| w == needle)
}
