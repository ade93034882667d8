//! One error type for the library; every message names the file, line or
//! field at fault and what was wrong with it.

use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    /// A scene file that does not parse or whose values are invalid; the
    /// message names the line or the field.
    #[error("{path}: {message}")]
    Scene { path: PathBuf, message: String },
    #[error("{path}:{line}: {message}")]
    Line {
        path: PathBuf,
        line: usize,
        message: String,
    },
    #[error("GPU: {0}")]
    Gpu(String),
    /// The scene does not fit the adapter's memory or binding limits; the
    /// message says what and by how much (`--device auto` then renders on
    /// the CPU path).
    #[error("GPU: {0}")]
    GpuLimit(String),
    /// The driver cut the shader's loops short (Mesa's llvmpipe ends loops
    /// after 65535 iterations an invocation group), so the answers would
    /// be wrong; the message says where. The CPU path has no such limit,
    /// and each front end says how to ask for it in its own terms (the
    /// CLI's `--device cpu`, Python's `device="cpu"`).
    #[error("GPU: {0}")]
    LoopsCut(String),
    #[error("{0}")]
    Usage(String),
}

pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    pub fn io(path: &Path, source: std::io::Error) -> Self {
        Error::Io {
            path: path.to_path_buf(),
            source,
        }
    }

    pub fn scene(path: &Path, message: impl Into<String>) -> Self {
        Error::Scene {
            path: path.to_path_buf(),
            message: message.into(),
        }
    }
}
