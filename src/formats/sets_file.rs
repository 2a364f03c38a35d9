//! The sets file (TOML) read from disk; its schema and evaluation are in
//! [`crate::mesh::sets`].

use crate::error::Result;
use crate::mesh::SetsConfig;
use std::path::Path;

impl SetsConfig {
    /// Reads and checks a sets file ([`SetsConfig::parse`]).
    pub fn read(path: &Path) -> Result<Self> {
        let text = crate::formats::read_input_text(path)?;
        Self::parse(path, &text)
    }
}
