//! Which labels of a label map make the shape: by number (`31`), several as one (`1,7`: a
//! bone with its lesions), or by name (`vertebrae_L1`) from a label table.

use crate::error::{Error, Result};
use std::collections::BTreeMap;

/// The labels asked for, as the user wrote them (numbers or names, comma-separated).
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct LabelChoice {
    /// Each item: a label number or a name.
    pub items: Vec<LabelItem>,
}

/// One item of a [`LabelChoice`].
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(untagged)]
pub enum LabelItem {
    /// A label value.
    Number(i64),
    /// A label's name in the label table.
    Name(String),
}

impl std::str::FromStr for LabelChoice {
    type Err = Error;

    /// `31`, `1,7`, `vertebrae_L1`, `vertebrae_L1,vertebrae_L2`.
    fn from_str(s: &str) -> Result<Self> {
        let items: Vec<LabelItem> = s
            .split(',')
            .map(str::trim)
            .filter(|t| !t.is_empty())
            .map(|t| match t.parse::<i64>() {
                Ok(n) => LabelItem::Number(n),
                Err(_) => LabelItem::Name(t.to_string()),
            })
            .collect();
        if items.is_empty() {
            return Err(Error::Parameter(format!(
                "label {s:?}: give a label number (31), several (1,7) or a name (vertebrae_L1)"
            )));
        }
        Ok(LabelChoice { items })
    }
}

impl std::fmt::Display for LabelChoice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let parts: Vec<String> = self
            .items
            .iter()
            .map(|i| match i {
                LabelItem::Number(n) => n.to_string(),
                LabelItem::Name(s) => s.clone(),
            })
            .collect();
        f.write_str(&parts.join(","))
    }
}

/// Label values and their names (a CSV `label,name` as TotalSegmentator's classes, or the
/// segment names of a Slicer `.seg.nrrd`).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LabelTable {
    /// Name of each label value.
    pub names: BTreeMap<i64, String>,
}

impl LabelTable {
    /// The label values of `choice`; `source` names the label map in messages.
    ///
    /// # Errors
    /// [`Error::Parameter`] for a name that is not in the table (listing the names known).
    pub fn resolve(&self, choice: &LabelChoice, source: &str) -> Result<Vec<i64>> {
        let mut out = Vec::new();
        for item in &choice.items {
            match item {
                LabelItem::Number(n) => out.push(*n),
                LabelItem::Name(name) => {
                    let found = self
                        .names
                        .iter()
                        .find(|(_, v)| v.eq_ignore_ascii_case(name))
                        .map(|(k, _)| *k);
                    match found {
                        Some(k) => out.push(k),
                        None if self.names.is_empty() => {
                            return Err(Error::Parameter(format!(
                                "{source}: label {name:?} is a name, but there is no label table \
                                 (give --label-table NAMES.csv with label,name rows, or the label's number)"
                            )));
                        }
                        None => {
                            let known: Vec<String> = self
                                .names
                                .values()
                                .take(20)
                                .map(|n| crate::geometry::display_name(n))
                                .collect();
                            return Err(Error::Parameter(format!(
                                "{source}: no label named {:?}; the table names {}{}",
                                crate::geometry::display_name(name),
                                known.join(", "),
                                if self.names.len() > 20 { ", ..." } else { "" }
                            )));
                        }
                    }
                }
            }
        }
        out.sort_unstable();
        out.dedup();
        Ok(out)
    }

    /// The table's name of label `v`, if any.
    pub fn name(&self, v: i64) -> Option<&str> {
        self.names.get(&v).map(String::as_str)
    }
}
