//! The sets file (TOML) read from disk; its schema and evaluation are in
//! [`crate::mesh::sets`].

use crate::error::{Error, Result};
use crate::mesh::SetsConfig;
use std::path::Path;

impl SetsConfig {
    /// Reads and checks a sets file ([`SetsConfig::parse`]).
    pub fn read(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Self::parse(path, &text)
    }
}
