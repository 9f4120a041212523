//! The one error type of the crate.
//!
//! Every fallible public function returns [`Result<T>`](crate::Result). Messages are written for the
//! person who passed the input: they say what was wrong and where (a point index, a line number, a
//! byte offset, a tensor name), so the same text can be shown in a terminal or thrown as a JS `Error`.

/// Everything that can go wrong in arps.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A point cloud that cannot be registered: empty, too few points, non-finite coordinates,
    /// a flat buffer whose length is not a multiple of 3, or a degenerate extent.
    #[error("invalid point cloud: {0}")]
    InvalidCloud(String),
    /// A file that could not be parsed. `format` names the reader (`PLY`, `PCD`, ...), `message`
    /// says what and where (line, byte offset, element).
    #[error("{format} parse error: {message}")]
    Parse {
        /// The format whose reader failed.
        format: &'static str,
        /// What went wrong, and where.
        message: String,
    },
    /// A weights file that is corrupt, truncated, of an unknown version, or does not match the
    /// model configuration it declares (the first mismatching tensor is named).
    #[error("weights: {0}")]
    Weights(String),
    /// An option outside its documented range.
    #[error("invalid option: {0}")]
    InvalidOption(String),
    /// Input larger than the engine's budgets ([`crate::limits`]): the message names the limit,
    /// the input's size, and how to make it fit (downsampling, `voxelSize`).
    #[error("too large: {0}")]
    TooLarge(String),
    /// A computation that produced NaN or infinity from inputs that passed their checks.
    #[error("numerical failure: {0}")]
    Numerical(String),
    /// An operating-system I/O error (native only: reading a path, writing a file).
    #[error("I/O error: {0}")]
    Io(#[from] std::io::Error),
}

impl Error {
    /// Shorthand for a [`Error::Parse`].
    pub fn parse(format: &'static str, message: impl Into<String>) -> Self {
        Error::Parse { format, message: message.into() }
    }
}

/// `Result` with the crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
