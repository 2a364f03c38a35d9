//! Errors of the library: problems in the data, never broken caller contracts (those assert).

use std::path::PathBuf;

/// Every way the data given to atlasmesh can be wrong. Each variant says what went wrong, where,
/// and (in its doc) how to fix it.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file could not be read or written. Check the path, its permissions and the free
    /// space. (The I/O error is in the message, not a separate source, so that it is printed
    /// once.)
    #[error("{path}: {error}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        error: std::io::Error,
    },
    /// A file is malformed: its content does not follow its format. Fix the file at the given
    /// line (1-based; 0 when the position is not a line, as in binary files).
    #[error("{path}:{line}: {message}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// The line (1-based; 0 when the position is not a line).
        line: usize,
        /// What is wrong there.
        message: String,
    },
    /// A shape cannot be used by the method (too few points, NaN, degenerate, mismatched
    /// counts). The message names the shape and the problem.
    #[error("shape {name}: {message}")]
    InvalidShape {
        /// The shape's name (its file stem, or its id in a CSV).
        name: String,
        /// What is wrong with it.
        message: String,
    },
    /// The population as a whole cannot be used (too few shapes, different point counts,
    /// mixed dimensions, no variance).
    #[error("population: {0}")]
    Population(String),
    /// A parameter is out of its range. The message says which and the allowed range.
    #[error("parameter: {0}")]
    Parameter(String),
    /// Meshing failed or produced an invalid mesh (self-intersecting outline, inverted
    /// elements). Try a smaller element size or check the outline.
    #[error("mesh: {0}")]
    Mesh(String),
    /// An atlas file is not a valid atlasmesh atlas (wrong format version, missing tensor).
    /// Rebuild the atlas with `atlasmesh build`.
    #[error("{path}: not a valid atlas: {message}")]
    Atlas {
        /// The atlas file.
        path: PathBuf,
        /// What is wrong with it.
        message: String,
    },
    /// A numerical step failed (singular system, SVD did not converge). Usually the input is
    /// degenerate: identical shapes, collinear points.
    #[error("numerics: {0}")]
    Numerical(String),
    /// The fit of a subject did not converge to a shape near it: the subject is far outside
    /// the model (another anatomy, a segmentation error, a part missing: try `--partial`),
    /// so no mesh was written for it. The message gives the misfit and the bound.
    #[error("subject {name}: the fit did not converge: {message}")]
    NotConverged {
        /// The subject's name.
        name: String,
        /// The misfit and the bound.
        message: String,
    },
}

/// Short for `Result<T, atlasmesh::Error>`.
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    /// Exit code of the command-line tool for this class of error: 2 bad input, 3 I/O,
    /// 4 invalid mesh, 5 did not converge (a fit, or a numerical step on degenerate data).
    /// (6: a batch in which some subjects failed; see the CLI.)
    pub fn exit_code(&self) -> u8 {
        match self {
            Error::Io { .. } => 3,
            Error::Parse { .. }
            | Error::InvalidShape { .. }
            | Error::Population(_)
            | Error::Parameter(_)
            | Error::Atlas { .. } => 2,
            Error::Mesh(_) => 4,
            Error::Numerical(_) | Error::NotConverged { .. } => 5,
        }
    }

    /// An [`Error::Io`] on `path`.
    pub fn io(path: impl Into<PathBuf>, error: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            error,
        }
    }

    /// An [`Error::Parse`] at `line` of `path`.
    pub fn parse(path: impl Into<PathBuf>, line: usize, message: impl Into<String>) -> Self {
        Error::Parse {
            path: path.into(),
            line,
            message: message.into(),
        }
    }

    /// An [`Error::Parse`] of `path` for a TOML error `e` in its `text`, at the error's line.
    pub fn toml(path: impl Into<PathBuf>, text: &str, e: &toml::de::Error) -> Self {
        let line = e
            .span()
            .map(|s| text[..s.start.min(text.len())].lines().count().max(1))
            .unwrap_or(0);
        Error::parse(path, line, e.message().to_string())
    }

    /// An [`Error::InvalidShape`] of the shape `name`.
    pub fn shape(name: impl Into<String>, message: impl Into<String>) -> Self {
        Error::InvalidShape {
            name: name.into(),
            message: message.into(),
        }
    }
}
