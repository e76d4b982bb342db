//! Why a render could not start or finish.

use std::path::PathBuf;

/// A render that could not be done.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The crop window does not lie inside the camera's film.
    #[error("crop window {width}x{height} at ({x}, {y}) does not fit in the {film_width}x{film_height} film")]
    CropWindow {
        /// Left column.
        x: u32,
        /// Top row.
        y: u32,
        /// Width.
        width: u32,
        /// Height.
        height: u32,
        /// The film's width.
        film_width: u32,
        /// The film's height.
        film_height: u32,
    },
    /// The worker threads could not start.
    #[error("cannot start {threads} worker threads: {message}")]
    Threads {
        /// How many were asked for (0: one per core).
        threads: usize,
        /// The pool's error.
        message: String,
    },
    /// A saved film that does not fit the render resumed from it.
    #[error("cannot resume: {0}")]
    Resume(String),
    /// The Neumann-series terms were asked of an integrator that does not separate them.
    #[error("the {integrator} integrator does not separate the terms of the Neumann series")]
    NoTerms {
        /// The integrator's name.
        integrator: &'static str,
    },
    /// The integrator cannot render this scene's setup (say, light tracing through an
    /// orthographic camera).
    #[error("{0}")]
    Unsupported(String),
    /// Light tracing needs something to start paths from.
    #[error("light tracing needs at least one emitter")]
    NoEmitters,
    /// The radiosity solve failed (the scene has no patches, say).
    #[error("radiosity: {0}")]
    Radiosity(crate::integrator::radiosity::RadiosityError),
    /// An output the integrator writes could not be written.
    #[error("cannot write '{}': {source}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
}
