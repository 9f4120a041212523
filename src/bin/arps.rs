//! The `arps` command-line tool.
fn main() {
    eprintln!("arps: CLI not built yet");
    std::process::exit(2);
}
