//! The library's error type: every fallible function of the pipeline, the formats and the
//! evaluation returns [`Result`]. The 3D viewer has its own, [`crate::render::RenderError`].

use std::path::PathBuf;

/// Everything that can go wrong on user data, with a message a person can act on.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The bytes are not an image we can decode (not PNG/JPEG, or truncated).
    #[error("cannot decode image: {0}")]
    Decode(String),
    /// An image is smaller than the pipeline can work with.
    #[error("image is too small: {width}×{height} pixels (at least {min}×{min} needed)")]
    TooSmall {
        width: usize,
        height: usize,
        min: usize,
    },
    /// The two frames of a pair differ in size.
    #[error(
        "the two frames differ in size: frame 1 is {w1}×{h1}, frame 2 is {w2}×{h2}; both must be the same size"
    )]
    SizeMismatch {
        w1: usize,
        h1: usize,
        w2: usize,
        h2: usize,
    },
    /// A file in one of our formats (PFM, .flo, PLY, PNG, case layout) is malformed.
    #[error("invalid {format} data: {reason}")]
    Format {
        format: &'static str,
        reason: String,
    },
    /// The two frames carry no usable parallax (identical frames, pure rotation, too little
    /// reliable flow), so depth is unobservable.
    #[error("no parallax: depth cannot be recovered ({0})")]
    NoParallax(String),
    /// A parameter is out of its valid range.
    #[error("invalid parameter: {0}")]
    InvalidParameter(String),
}

/// Shorthand for results with the crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// Wraps an I/O error with the path it concerns.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }

    /// A malformed-file error for `format` with a reason.
    pub fn format(format: &'static str, reason: impl Into<String>) -> Self {
        Error::Format {
            format,
            reason: reason.into(),
        }
    }
}
