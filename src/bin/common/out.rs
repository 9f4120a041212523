//! Printing to stdout for the command-line tools. `println!` panics when the reader has gone
//! (`arps info model.safetensors | head -1`); `out!` ends the process quietly with status 0
//! instead, like other Unix tools, and reports any other write error on stderr with status 1.

/// `println!` for the CLI: on a closed pipe the process exits quietly (status 0).
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::out::line(format_args!($($arg)*))
    };
}

/// Writes one line to stdout; see the module doc for what happens when that fails.
pub fn line(args: std::fmt::Arguments) {
    use std::io::Write;
    let mut stdout = std::io::stdout().lock();
    if let Err(e) = stdout.write_fmt(args).and_then(|()| stdout.write_all(b"\n")) {
        if e.kind() == std::io::ErrorKind::BrokenPipe {
            std::process::exit(0);
        }
        eprintln!("{}: writing to stdout: {e}", env!("CARGO_BIN_NAME"));
        std::process::exit(1);
    }
}
