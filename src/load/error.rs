//! Errors reading the files a scene names (meshes, images): which file, where in it (for text
//! formats, the line) and what was wrong.

use std::path::PathBuf;

/// A file that could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// The file could not be read at all.
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The file's contents are not what its format allows; `line` for text formats.
    #[error("{}{}: {message}", path.display(), line.map(|l| format!(":{l}")).unwrap_or_default())]
    Format {
        /// The file.
        path: PathBuf,
        /// 1-based line of the problem, where the format has lines.
        line: Option<usize>,
        /// What was expected.
        message: String,
    },
    /// The file's extension names no format neumann reads.
    #[error("{}: {message}", path.display())]
    Unsupported {
        /// The file.
        path: PathBuf,
        /// What is supported.
        message: String,
    },
}

impl LoadError {
    /// A format error in `path` without a line.
    pub fn format(path: &std::path::Path, message: impl Into<String>) -> LoadError {
        LoadError::Format { path: path.to_path_buf(), line: None, message: message.into() }
    }

    /// The file could not be read.
    pub fn io(path: &std::path::Path, source: std::io::Error) -> LoadError {
        LoadError::Io { path: path.to_path_buf(), source }
    }
}
