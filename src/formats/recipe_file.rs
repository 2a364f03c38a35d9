//! The material recipe (TOML) read from disk; its schema and law are in
//! [`crate::materials`].

use crate::error::Result;
use crate::materials::MaterialRecipe;
use std::path::Path;

impl MaterialRecipe {
    /// Reads and checks a recipe file ([`MaterialRecipe::parse`]).
    pub fn read(path: &Path) -> Result<Self> {
        let text = crate::formats::read_input_text(path)?;
        Self::parse(path, &text)
    }
}
