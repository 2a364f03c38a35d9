//! CSV tables with named columns, as spreadsheets, R (`write.csv`, quoted fields) and pandas
//! write them: the columns atlasmesh needs are found by name (case-insensitive, with the usual
//! aliases, or as the user maps them: [`CsvColumns`]), other columns are ignored.

use crate::error::{Error, Result};
use std::collections::BTreeMap;
use std::path::Path;

/// The roles a column can have, with the names recognised for each.
pub const ROLES: [(&str, &[&str]); 7] = [
    ("shape", &["shape", "name", "specimen", "subject"]),
    ("point", &["point", "landmark", "id", "lm"]),
    ("index", &["index"]),
    ("index1", &["index1"]),
    ("x", &["x"]),
    ("y", &["y"]),
    ("z", &["z"]),
];

/// Which column holds which role, where the header's names are not the usual ones:
/// `shape=specimen,point=lm_id,x=X,y=Y`.
#[derive(Clone, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct CsvColumns(BTreeMap<String, String>);

impl std::str::FromStr for CsvColumns {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let mut map = BTreeMap::new();
        for pair in s.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            let (role, name) = pair
                .split_once('=')
                .ok_or_else(|| format!("{pair:?}: ROLE=COLUMN expected (e.g. shape=specimen)"))?;
            let role = role.trim().to_ascii_lowercase();
            if !ROLES.iter().any(|(r, _)| *r == role) {
                return Err(format!(
                    "{role:?} is not a column role; roles: {}",
                    ROLES.map(|(r, _)| r).join(", ")
                ));
            }
            let name = unquote(name).to_lowercase();
            if let Some((other, _)) = map.iter().find(|(_, n)| **n == name) {
                return Err(format!(
                    "{other} and {role} both name the column {name:?}; one column a role"
                ));
            }
            map.insert(role, name);
        }
        Ok(CsvColumns(map))
    }
}

/// Refuses what a plain split on commas would misread: a quoted field holding a comma (R's
/// `"s,1"`) or an escaped quote (`""`).
fn check_quotes(line: &str) -> std::result::Result<(), String> {
    if !line.contains('"') {
        return Ok(());
    }
    for f in line.split(',') {
        let t = f.trim();
        let inner = t.strip_prefix('"').and_then(|g| g.strip_suffix('"'));
        let bad = match inner {
            Some(g) => g.contains('"'),
            None => t.contains('"'),
        };
        if bad || t == "\"" {
            return Err(format!(
                "a quoted field holds a comma or a quote ({f:?}): not read; write names without \
                 commas or quotes (R: write.csv(..., quote = FALSE) after renaming)"
            ));
        }
    }
    Ok(())
}

/// A field without its surrounding quotes and spaces.
fn unquote(f: &str) -> &str {
    let f = f.trim();
    f.strip_prefix('"')
        .and_then(|g| g.strip_suffix('"'))
        .unwrap_or(f)
        .trim()
}

/// A parsed table: the header's names (lower case) and the rows' fields.
pub(crate) struct Table<'a> {
    pub header: Vec<String>,
    /// (line number, fields)
    pub rows: Vec<(usize, Vec<&'a str>)>,
    columns: CsvColumns,
}

impl<'a> Table<'a> {
    /// Splits `text` into its header and rows (blank lines skipped; every row as many fields
    /// as the header).
    pub fn parse(path: &Path, text: &'a str, columns: &CsvColumns) -> Result<Self> {
        let mut lines = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty());
        let Some((_, header)) = lines.next() else {
            return Err(Error::parse(
                path,
                1,
                "empty file; a header line was expected",
            ));
        };
        let header: Vec<String> = header
            .trim_start_matches('\u{feff}')
            .split(',')
            .map(|c| unquote(c).to_lowercase())
            .collect();
        for (k, h) in header.iter().enumerate() {
            if !h.is_empty() && header[..k].contains(h) {
                return Err(Error::parse(
                    path,
                    1,
                    format!("the header names the column {h:?} twice"),
                ));
            }
        }
        let mut rows = Vec::new();
        for (i, l) in lines {
            check_quotes(l).map_err(|m| Error::parse(path, i + 1, m))?;
            let f: Vec<&str> = l.split(',').map(unquote).collect();
            if f.len() != header.len() {
                return Err(Error::parse(
                    path,
                    i + 1,
                    format!(
                        "{} fields, {} expected (as in the header)",
                        f.len(),
                        header.len()
                    ),
                ));
            }
            rows.push((i + 1, f));
        }
        Ok(Table {
            header,
            rows,
            columns: columns.clone(),
        })
    }

    /// The column of `role`: the one mapped to it, else the first with one of its names.
    pub fn column(&self, path: &Path, role: &str) -> Result<Option<usize>> {
        if let Some(name) = self.columns.0.get(role) {
            return self
                .header
                .iter()
                .position(|h| h == name)
                .map(Some)
                .ok_or_else(|| {
                    Error::parse(
                        path,
                        1,
                        format!(
                            "no column {name:?} (given for {role}); the header has {}",
                            self.header.join(",")
                        ),
                    )
                });
        }
        let names = ROLES
            .iter()
            .find(|(r, _)| *r == role)
            .map_or(&[][..], |(_, n)| *n);
        Ok(self.header.iter().position(|h| names.contains(&h.as_str())))
    }

    /// The column of `role`, which the table must have.
    pub fn required(&self, path: &Path, role: &str, expected: &str) -> Result<usize> {
        self.column(path, role)?.ok_or_else(|| {
            Error::parse(
                path,
                1,
                format!(
                    "no {role} column in the header {:?}; expected {expected} (other columns are ignored; --columns maps other names)",
                    self.header.join(",")
                ),
            )
        })
    }
}
