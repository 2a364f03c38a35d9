//! The load case file (TOML) read from disk; its schema and application are in
//! [`crate::mesh::LoadCase`].

use crate::error::Result;
use crate::mesh::LoadCase;
use std::path::Path;

impl LoadCase {
    /// Reads and checks a load case file ([`LoadCase::parse`]).
    pub fn read(path: &Path) -> Result<Self> {
        let text = crate::formats::read_input_text(path)?;
        Self::parse(path, &text)
    }
}
