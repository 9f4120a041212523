//! The one error type of the crate.
//!
//! Every fallible public function returns [`Result<T>`](crate::Result). Messages are written for the
//! person who passed the input: they say what was wrong and where (a point index, a line number, a
//! byte offset, a tensor name), so the same text can be shown in a terminal or thrown as a JS `Error`.

/// Everything that can go wrong in arps. New kinds may be added (it is `#[non_exhaustive]`):
/// a `match` on it needs a `_` arm.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
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
    /// A file that was read but cannot be written moved as it is (`io::transform_file`, the CLI's
    /// `--aligned`): a field that cannot hold moved coordinates, or a layout whose bytes would
    /// change. `format` names the file's format, `message` what stands in the way and what to do.
    #[error("{format} file cannot be moved as it is: {message}")]
    Unmovable {
        /// The format of the file.
        format: &'static str,
        /// What stands in the way, and what to do instead.
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
    /// The registration was cancelled through its [`Cancel`](crate::Cancel) handle.
    #[error("cancelled: the registration was stopped through its Cancel handle")]
    Cancelled,
}

impl Error {
    /// Shorthand for a [`Error::Parse`].
    pub fn parse(format: &'static str, message: impl Into<String>) -> Self {
        Error::Parse { format, message: message.into() }
    }

    /// Shorthand for an [`Error::Unmovable`].
    pub fn unmovable(format: &'static str, message: impl Into<String>) -> Self {
        Error::Unmovable { format, message: message.into() }
    }
}

/// `Result` with the crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// A number as messages write it: rounded to four significant digits, without trailing zeros
/// (`0.025`, `1235`, `123500`, `0.3333`), in exponent form when it rounds to below 1e-3 or to
/// 1e6 or more (`1.5e-7`, `2.5e300`), so that a tiny or huge value reads as what it is, neither
/// `0.000` nor three hundred digits; `inf`, `-inf` and `NaN` as they are.
pub(crate) fn num(x: f64) -> String {
    if !x.is_finite() || x == 0.0 {
        return if x == 0.0 { "0".into() } else { format!("{x}") };
    }
    let trim = |s: &str| match s.find('.') {
        Some(_) => s.trim_end_matches('0').trim_end_matches('.').to_string(),
        None => s.to_string(),
    };
    // four significant digits first; the form follows the rounded value's exponent
    let rounded = format!("{x:.3e}");
    let (mantissa, exponent) = rounded.split_once('e').unwrap_or((&rounded, "0"));
    let exponent: i32 = exponent.parse().unwrap_or(0);
    if (-3..6).contains(&exponent) {
        let value: f64 = rounded.parse().unwrap_or(x);
        let decimals = (3 - exponent).max(0) as usize;
        trim(&format!("{value:.decimals$}"))
    } else {
        format!("{}e{exponent}", trim(mantissa))
    }
}

#[cfg(test)]
mod tests {
    use super::num;

    #[test]
    fn numbers_in_messages_read_as_what_they_are() {
        for (x, s) in [
            (0.0, "0"),
            (0.025, "0.025"),
            (1234.0, "1234"),
            (1.0 / 3.0, "0.3333"),
            (-2.5, "-2.5"),
            (123_456.7, "123500"),
            (999_999.6, "1e6"),
            (0.000_999_96, "0.001"),
            (999.96, "1000"),
            (-0.000_012_3, "-1.23e-5"),
            (1e6, "1e6"),
            (1.5e-7, "1.5e-7"),
            (1e300, "1e300"),
            (1.0937500400699987e28, "1.094e28"),
            (f64::INFINITY, "inf"),
            (f64::NAN, "NaN"),
        ] {
            assert_eq!(num(x), s, "{x}");
        }
    }
}
