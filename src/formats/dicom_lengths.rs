//! A DICOM file's declared lengths checked before it is parsed. The DICOM parser atlasmesh
//! uses (dicom-parser) reserves and zeroes the length an element declares before it reads the
//! value, so a file of a few hundred bytes declaring a 2 GB element took 3 GB to be refused.
//! This walk reads only the element headers (PS3.5 §7: the file meta group in explicit VR
//! little endian, then the data set in the transfer syntax the meta group names) and refuses
//! any element, item or pixel fragment whose declared length reaches past the bytes that hold
//! it (the file's end, or the end of the item or sequence of defined length around it), so
//! that nothing the parser allocates is larger than the file (or, for a deflated data set,
//! than its inflated bytes, themselves within [`super::input::decode_budget`]).
//!
//! The walk follows the parser's rules, so that every header the parser reads is one this
//! walk checked: a sequence is an element of VR `SQ` (in implicit VR, by the standard data
//! dictionary) or any other element of undefined length; Pixel Data (7FE0,0010) of undefined
//! length is a sequence of fragments; the end of the data while a tag is expected ends the
//! data set. Structure the parser would refuse (an item header where an element was due, a
//! value running past its item) is refused here too, naming the byte.

use crate::error::{Error, Result};
use dicom_core::dictionary::{DataDictionary, DataDictionaryEntry};
use dicom_core::{Tag, VR};
use std::io::Read as _;
use std::path::Path;

/// Sequences nested deeper than this are refused (real objects nest a few levels).
const MAX_DEPTH: usize = 64;

/// The undefined length (PS3.5 §7.1.1).
const UNDEFINED: u32 = u32::MAX;

/// Checks every length the Part 10 file `bytes` (128-byte preamble, `DICM`, meta group, data
/// set) declares against the bytes that hold it; `path` names the file in the error.
///
/// # Errors
/// [`Error::Parse`] naming the file, the element (group, element) and its byte offset, and
/// both figures: a declared length beyond what is left, a meta group that is not explicit VR
/// little endian or has an element of undefined length, a deflated data set that inflates
/// beyond its budget, sequences nested deeper than 64 levels, an item header where an element
/// is due or the reverse.
pub(super) fn check_declared_lengths(path: &Path, bytes: &[u8]) -> Result<()> {
    let bad = |m: String| Error::parse(path, 0, m);
    if bytes.len() < 132 || &bytes[128..132] != b"DICM" {
        return Err(bad("no DICM mark after the 128-byte preamble".into()));
    }
    // The meta group: (0002,0000) of length 4 gives the group's length; its elements are read
    // until that many bytes are consumed, as the parser reads them.
    let mut meta = Walk::new(bytes, Syntax::EXPLICIT_LE);
    meta.pos = 132;
    let h = meta
        .header()
        .map_err(&bad)?
        .ok_or_else(|| bad("the file meta group is cut short".into()))?;
    if h.tag != Tag(0x0002, 0x0000) || h.len != 4 {
        return Err(bad(format!(
            "the file meta group does not start with its length (0002,0000) of 4 bytes, but \
             with {} of {} bytes",
            tag_text(h.tag),
            h.len
        )));
    }
    let group_length = u32::from_le_bytes(meta.take(4).map_err(&bad)?.try_into().unwrap_or([0; 4]));
    let start = meta.pos;
    let mut transfer_syntax = String::new();
    while meta.pos - start < group_length as usize {
        let h = meta
            .header()
            .map_err(&bad)?
            .ok_or_else(|| bad("the file meta group is cut short".into()))?;
        if h.len == UNDEFINED {
            return Err(bad(format!(
                "the file meta group's element {} has an undefined length",
                tag_text(h.tag)
            )));
        }
        let value = meta.value(&h, None).map_err(&bad)?;
        if h.tag == Tag(0x0002, 0x0010) {
            transfer_syntax = String::from_utf8_lossy(value)
                .trim_end_matches(['\0', ' '])
                .to_string();
        }
    }
    let rest = &bytes[meta.pos..];
    match transfer_syntax.as_str() {
        "1.2.840.10008.1.2" => Walk::new(rest, Syntax::IMPLICIT_LE).data_set(meta.pos),
        "1.2.840.10008.1.2.2" => Walk::new(rest, Syntax::EXPLICIT_BE).data_set(meta.pos),
        // Deflated explicit VR little endian: the data set is one raw deflate stream.
        "1.2.840.10008.1.2.1.99" | "1.2.840.10008.1.2.8.1" => {
            let budget = super::input::decode_budget(rest.len());
            let mut inflated = Vec::new();
            flate2::read::DeflateDecoder::new(rest)
                .take(budget as u64 + 1)
                .read_to_end(&mut inflated)
                .map_err(|e| bad(format!("the deflated data set is corrupt: {e}")))?;
            if inflated.len() > budget {
                return Err(bad(format!(
                    "the deflated data set inflates beyond {} MB from {} kB (a decompression \
                     bomb; set ATLASMESH_MAX_DECODED_BYTES to raise it)",
                    budget >> 20,
                    rest.len() >> 10
                )));
            }
            Walk::new(&inflated, Syntax::EXPLICIT_LE).data_set(0)
        }
        _ => Walk::new(rest, Syntax::EXPLICIT_LE).data_set(meta.pos),
    }
    .map_err(bad)
}

/// How the data set is encoded.
#[derive(Clone, Copy)]
struct Syntax {
    explicit: bool,
    big_endian: bool,
}

impl Syntax {
    const EXPLICIT_LE: Self = Syntax {
        explicit: true,
        big_endian: false,
    };
    const EXPLICIT_BE: Self = Syntax {
        explicit: true,
        big_endian: true,
    };
    const IMPLICIT_LE: Self = Syntax {
        explicit: false,
        big_endian: false,
    };
}

/// An element or item header.
struct Header {
    tag: Tag,
    /// The VR: explicit, or from the dictionary (implicit); `None` for items and delimiters.
    vr: Option<VR>,
    len: u32,
    /// Where the header starts (for messages).
    at: usize,
}

/// How a level of the walk ended.
#[derive(PartialEq)]
enum End {
    /// Its delimiter, or its defined length, was reached.
    Closed,
    /// The data ended where a tag was due: the parser ends the data set there.
    Data,
}

/// The walk over one encoded data set.
struct Walk<'a> {
    buf: &'a [u8],
    pos: usize,
    syntax: Syntax,
    /// Where `buf` starts in the file (for messages).
    base: usize,
    depth: usize,
}

type Step<T> = std::result::Result<T, String>;

impl<'a> Walk<'a> {
    fn new(buf: &'a [u8], syntax: Syntax) -> Self {
        Walk {
            buf,
            pos: 0,
            syntax,
            base: 0,
            depth: 0,
        }
    }

    /// The data set from the walk's start to the end of the data; `base` is its offset in the
    /// file.
    fn data_set(mut self, base: usize) -> Step<()> {
        self.base = base;
        self.elements(None, false).map(|_| ())
    }

    fn take(&mut self, n: usize) -> Step<&'a [u8]> {
        let b = self
            .buf
            .get(self.pos..self.pos + n)
            .ok_or_else(|| format!("cut short at byte {}", self.base + self.pos))?;
        self.pos += n;
        Ok(b)
    }

    fn u16(&mut self) -> Step<u16> {
        let b = self.take(2)?;
        Ok(if self.syntax.big_endian {
            u16::from_be_bytes([b[0], b[1]])
        } else {
            u16::from_le_bytes([b[0], b[1]])
        })
    }

    fn u32(&mut self) -> Step<u32> {
        let b = self.take(4)?;
        let b = [b[0], b[1], b[2], b[3]];
        Ok(if self.syntax.big_endian {
            u32::from_be_bytes(b)
        } else {
            u32::from_le_bytes(b)
        })
    }

    /// The next header; `None` where fewer than 4 bytes are left (no tag: the end of the
    /// data, as the parser takes it).
    fn header(&mut self) -> Step<Option<Header>> {
        if self.buf.len() - self.pos.min(self.buf.len()) < 4 {
            return Ok(None);
        }
        let at = self.pos;
        let tag = Tag(self.u16()?, self.u16()?);
        if tag.0 == 0xFFFE {
            // Items and delimiters: a 4-byte length, no VR, in every syntax.
            let len = self.u32()?;
            return Ok(Some(Header {
                tag,
                vr: None,
                len,
                at,
            }));
        }
        if !self.syntax.explicit {
            let len = self.u32()?;
            let vr = if tag == Tag(0x7FE0, 0x0010) {
                VR::OW
            } else {
                dicom_dictionary_std::StandardDataDictionary
                    .by_tag(tag)
                    .map(|e| e.vr().relaxed())
                    .unwrap_or(VR::UN)
            };
            return Ok(Some(Header {
                tag,
                vr: Some(vr),
                len,
                at,
            }));
        }
        let code = self.take(2)?;
        let vr = VR::from_binary([code[0], code[1]]).unwrap_or(VR::UN);
        // PS3.5 Table 7.1-2: these VRs have a 2-byte length; every other (and an unknown VR,
        // taken as UN) two reserved bytes and a 4-byte length.
        let short = matches!(
            vr,
            VR::AE
                | VR::AS
                | VR::AT
                | VR::CS
                | VR::DA
                | VR::DS
                | VR::DT
                | VR::FL
                | VR::FD
                | VR::IS
                | VR::LO
                | VR::LT
                | VR::PN
                | VR::SH
                | VR::SL
                | VR::SS
                | VR::ST
                | VR::TM
                | VR::UI
                | VR::UL
                | VR::US
        );
        let len = if short {
            u32::from(self.u16()?)
        } else {
            self.take(2)?;
            self.u32()?
        };
        Ok(Some(Header {
            tag,
            vr: Some(vr),
            len,
            at,
        }))
    }

    /// The value of the defined-length header `h`, which must end by `end` (the end of the
    /// item or sequence around it) or the data's: its bytes.
    fn value(&mut self, h: &Header, end: Option<usize>) -> Step<&'a [u8]> {
        let left = end
            .unwrap_or(usize::MAX)
            .min(self.buf.len())
            .saturating_sub(self.pos);
        if h.len as usize > left {
            return Err(format!(
                "the element {} at byte {} declares {} bytes, but only {left} are left{}",
                tag_text(h.tag),
                self.base + h.at,
                h.len,
                if end.is_some() {
                    " in the item or sequence around it"
                } else {
                    " in the file"
                }
            ));
        }
        // The parser reads whole values of a binary VR and moves on by the declared length:
        // a length that is not a whole number of values leaves it reading the next header
        // from inside this value (pydicom refuses such a value too).
        if let Some(size) = h.vr.and_then(value_size)
            && !(h.len as usize).is_multiple_of(size)
        {
            return Err(format!(
                "the element {} at byte {} declares {} bytes, not a whole number of {:?} values \
                 of {size} bytes",
                tag_text(h.tag),
                self.base + h.at,
                h.len,
                h.vr.unwrap_or(VR::UN)
            ));
        }
        self.take(h.len as usize)
    }

    /// The end (exclusive) of a container of defined length `len` starting here, within
    /// `outer`.
    fn bounded(&self, h: &Header, outer: Option<usize>) -> Step<Option<usize>> {
        if h.len == UNDEFINED {
            return Ok(None);
        }
        let end = outer.unwrap_or(self.buf.len()).min(self.buf.len());
        let left = end.saturating_sub(self.pos);
        if h.len as usize > left {
            return Err(format!(
                "the {} {} at byte {} declares {} bytes, but only {left} are left",
                if h.tag.0 == 0xFFFE {
                    "item"
                } else {
                    "sequence"
                },
                tag_text(h.tag),
                self.base + h.at,
                h.len
            ));
        }
        Ok(Some(self.pos + h.len as usize))
    }

    /// Where a level of defined length `end` stands: `Some(Closed)` at its end, an error past
    /// it.
    fn at_end(&self, end: Option<usize>) -> Step<Option<End>> {
        match end {
            Some(e) if self.pos == e => Ok(Some(End::Closed)),
            Some(e) if self.pos > e => Err(format!(
                "a value runs past the end of its item or sequence (byte {}, the end at {})",
                self.base + self.pos,
                self.base + e
            )),
            _ => Ok(None),
        }
    }

    fn deeper(&mut self) -> Step<()> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(format!(
                "sequences nested deeper than {MAX_DEPTH} levels (byte {})",
                self.base + self.pos
            ));
        }
        Ok(())
    }

    /// Data elements up to `end` (an item or the data set of defined length), up to an item
    /// delimiter (`in_item`, an item of undefined length), or to the end of the data.
    fn elements(&mut self, end: Option<usize>, in_item: bool) -> Step<End> {
        loop {
            if let Some(e) = self.at_end(end)? {
                return Ok(e);
            }
            let Some(h) = self.header()? else {
                return Ok(End::Data);
            };
            if h.tag == Tag(0xFFFE, 0xE00D) {
                if in_item {
                    return Ok(End::Closed);
                }
                continue; // outside any item: the parser passes over it
            }
            if h.tag.0 == 0xFFFE {
                return Err(format!(
                    "an item header {} at byte {} where a data element is due",
                    tag_text(h.tag),
                    self.base + h.at
                ));
            }
            let flow = if h.tag == Tag(0x7FE0, 0x0010) && h.len == UNDEFINED {
                self.fragments()?
            } else if h.vr == Some(VR::SQ) || h.len == UNDEFINED {
                let inner = self.bounded(&h, end)?;
                self.deeper()?;
                let f = self.sequence(inner)?;
                self.depth -= 1;
                f
            } else {
                self.value(&h, end)?;
                End::Closed
            };
            if flow == End::Data {
                return Ok(End::Data);
            }
        }
    }

    /// A sequence's items, up to `end` (defined length) or its delimiter.
    fn sequence(&mut self, end: Option<usize>) -> Step<End> {
        loop {
            if let Some(e) = self.at_end(end)? {
                return Ok(e);
            }
            let Some(h) = self.header()? else {
                return Ok(End::Data);
            };
            match h.tag {
                Tag(0xFFFE, 0xE000) => {
                    let inner = self.bounded(&h, end)?;
                    self.deeper()?;
                    let f = self.elements(inner, true)?;
                    self.depth -= 1;
                    if f == End::Data {
                        return Ok(End::Data);
                    }
                }
                Tag(0xFFFE, 0xE0DD) => return Ok(End::Closed),
                other => {
                    return Err(format!(
                        "{} at byte {} where a sequence's item is due",
                        tag_text(other),
                        self.base + h.at
                    ));
                }
            }
        }
    }

    /// Encapsulated pixel data: fragments of defined length up to the sequence delimiter.
    fn fragments(&mut self) -> Step<End> {
        loop {
            let Some(h) = self.header()? else {
                return Ok(End::Data);
            };
            match h.tag {
                Tag(0xFFFE, 0xE000) if h.len != UNDEFINED => {
                    self.value(&h, None)?;
                }
                Tag(0xFFFE, 0xE0DD) => return Ok(End::Closed),
                other => {
                    return Err(format!(
                        "{} of length {} at byte {} where a pixel data fragment is due",
                        tag_text(other),
                        h.len,
                        self.base + h.at
                    ));
                }
            }
        }
    }
}

/// The size of one value of a binary VR (PS3.5 Table 6.2-1); `None` for text and bytes.
fn value_size(vr: VR) -> Option<usize> {
    match vr {
        VR::US | VR::SS | VR::OW => Some(2),
        VR::UL | VR::SL | VR::FL | VR::AT | VR::OF | VR::OL => Some(4),
        VR::FD | VR::OD | VR::OV | VR::SV | VR::UV => Some(8),
        _ => None,
    }
}

/// `(gggg,eeee)`.
fn tag_text(t: Tag) -> String {
    format!("({:04X},{:04X})", t.0, t.1)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A Part 10 file: preamble, the meta group naming `ts`, then `data`.
    fn file(ts: &str, data: &[u8]) -> Vec<u8> {
        let mut uid = ts.as_bytes().to_vec();
        if uid.len() % 2 == 1 {
            uid.push(0);
        }
        let mut meta = Vec::new();
        meta.extend_from_slice(&[0x02, 0x00, 0x10, 0x00, b'U', b'I']);
        meta.extend_from_slice(&(uid.len() as u16).to_le_bytes());
        meta.extend_from_slice(&uid);
        let mut out = vec![0u8; 128];
        out.extend_from_slice(b"DICM");
        out.extend_from_slice(&[0x02, 0x00, 0x00, 0x00, b'U', b'L', 4, 0]);
        out.extend_from_slice(&(meta.len() as u32).to_le_bytes());
        out.extend_from_slice(&meta);
        out.extend_from_slice(data);
        out
    }

    /// An explicit VR little endian element with a 4-byte length (`OB`, `SQ`, `UN`, ...).
    fn long(group: u16, element: u16, vr: &[u8; 2], len: u32) -> Vec<u8> {
        let mut v = Vec::new();
        v.extend_from_slice(&group.to_le_bytes());
        v.extend_from_slice(&element.to_le_bytes());
        v.extend_from_slice(vr);
        v.extend_from_slice(&[0, 0]);
        v.extend_from_slice(&len.to_le_bytes());
        v
    }

    fn item(element: u16, len: u32) -> Vec<u8> {
        let mut v = vec![0xFE, 0xFF];
        v.extend_from_slice(&element.to_le_bytes());
        v.extend_from_slice(&len.to_le_bytes());
        v
    }

    const EXPLICIT: &str = "1.2.840.10008.1.2.1";
    const IMPLICIT: &str = "1.2.840.10008.1.2";

    fn check(bytes: &[u8]) -> std::result::Result<(), String> {
        check_declared_lengths(Path::new("x.dcm"), bytes).map_err(|e| e.to_string())
    }

    #[test]
    fn lengths_within_the_file_pass_and_beyond_it_are_refused() {
        // A short-length element (US, 2 bytes) and an OB of 4 bytes.
        let mut ok = vec![0x28, 0x00, 0x10, 0x00, b'U', b'S', 2, 0, 8, 0];
        ok.extend(long(0x0009, 0x0010, b"OB", 4));
        ok.extend_from_slice(&[1, 2, 3, 4]);
        check(&file(EXPLICIT, &ok)).unwrap();
        // The same OB declaring 1.97 GB: refused, naming the element and both figures.
        let mut bomb = long(0x0009, 0x0010, b"OB", 0x754e_0002);
        bomb.extend_from_slice(&[0; 16]);
        let e = check(&file(EXPLICIT, &bomb)).unwrap_err();
        assert!(
            e.contains("(0009,0010)") && e.contains("1968046082") && e.contains("16 are left"),
            "{e}"
        );
        // Implicit VR: a 4-byte length.
        let mut imp = vec![0x09, 0x00, 0x10, 0x00];
        imp.extend_from_slice(&0x4000_0000u32.to_le_bytes());
        assert!(
            check(&file(IMPLICIT, &imp))
                .unwrap_err()
                .contains("declares")
        );
        // The meta group's own elements are checked too.
        let mut meta = file(EXPLICIT, &[]);
        let n = meta.len();
        meta[n - 22..n - 20].copy_from_slice(&0xFFF0u16.to_le_bytes());
        assert!(check(&meta).is_err());
    }

    #[test]
    fn a_binary_value_of_a_broken_length_is_refused() {
        // SamplesPerPixel as UL of 2 bytes (the fuzzer's finding: the parser read no value,
        // moved its count on by 2, and took the next bytes for a header declaring 1.3 GB).
        let mut v = vec![0x28, 0x00, 0x02, 0x00, b'U', b'L', 2, 0, 1, 0];
        v.extend_from_slice(&[0x28, 0x00, 0x04, 0x00, b'C', b'S', 2, 0, b'M', b'O']);
        let e = check(&file(EXPLICIT, &v)).unwrap_err();
        assert!(
            e.contains("(0028,0002)") && e.contains("whole number of UL"),
            "{e}"
        );
        // As US, 2 bytes are one value.
        v[4..6].copy_from_slice(b"US");
        check(&file(EXPLICIT, &v)).unwrap();
    }

    #[test]
    fn sequences_items_and_fragments_are_walked() {
        // An SQ of undefined length holding one item of undefined length, whose element
        // declares more than the file holds.
        let mut seq = long(0x0008, 0x1140, b"SQ", UNDEFINED);
        seq.extend(item(0xE000, UNDEFINED));
        seq.extend(long(0x0009, 0x0010, b"OB", 1 << 30));
        let e = check(&file(EXPLICIT, &seq)).unwrap_err();
        assert!(e.contains("(0009,0010)"), "{e}");
        // A well-formed one passes: the item delimiter, then the sequence delimiter.
        let mut good = long(0x0008, 0x1140, b"SQ", UNDEFINED);
        good.extend(item(0xE000, UNDEFINED));
        good.extend(long(0x0009, 0x0010, b"OB", 2));
        good.extend_from_slice(&[0, 0]);
        good.extend(item(0xE00D, 0));
        good.extend(item(0xE0DD, 0));
        check(&file(EXPLICIT, &good)).unwrap();
        // An item of defined length larger than its sequence of defined length.
        let mut nested = long(0x0008, 0x1140, b"SQ", 8);
        nested.extend(item(0xE000, 100));
        nested.extend_from_slice(&[0; 100]);
        let e = check(&file(EXPLICIT, &nested)).unwrap_err();
        assert!(e.contains("item (FFFE,E000)"), "{e}");
        // In implicit VR, a defined-length sequence is known by the dictionary: (0008,1140)
        // Referenced Image Sequence, its item's element declaring 1 GB.
        let mut inner = vec![0x09, 0x00, 0x10, 0x00];
        inner.extend_from_slice(&(1u32 << 30).to_le_bytes());
        let mut imp = vec![0x08, 0x00, 0x40, 0x11];
        imp.extend_from_slice(&(8 + inner.len() as u32).to_le_bytes());
        imp.extend(item(0xE000, inner.len() as u32));
        imp.extend(inner);
        let e = check(&file(IMPLICIT, &imp)).unwrap_err();
        assert!(
            e.contains("(0009,0010)") && e.contains("item or sequence"),
            "{e}"
        );
        // Encapsulated pixel data: the offset table, a fragment declaring 1 GB.
        let mut px = long(0x7FE0, 0x0010, b"OB", UNDEFINED);
        px.extend(item(0xE000, 0));
        px.extend(item(0xE000, 1 << 30));
        px.extend_from_slice(&[0; 8]);
        let e = check(&file("1.2.840.10008.1.2.4.90", &px)).unwrap_err();
        assert!(e.contains("(FFFE,E000)") && e.contains("1073741824"), "{e}");
        // Nesting without end is bounded.
        let mut deep = Vec::new();
        for _ in 0..100 {
            deep.extend(long(0x0008, 0x1140, b"SQ", UNDEFINED));
            deep.extend(item(0xE000, UNDEFINED));
        }
        assert!(
            check(&file(EXPLICIT, &deep))
                .unwrap_err()
                .contains("nested")
        );
    }

    #[test]
    fn a_deflated_data_set_is_walked_inflated() {
        use std::io::Write as _;
        let mut bomb = long(0x0009, 0x0010, b"OB", 1 << 30);
        bomb.extend_from_slice(&[0; 64]);
        let mut z = flate2::write::DeflateEncoder::new(Vec::new(), flate2::Compression::fast());
        z.write_all(&bomb).unwrap();
        let e = check(&file("1.2.840.10008.1.2.1.99", &z.finish().unwrap())).unwrap_err();
        assert!(
            e.contains("(0009,0010)") && e.contains("64 are left"),
            "{e}"
        );
    }
}
