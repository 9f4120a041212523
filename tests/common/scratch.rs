//! Scratch directories for tests that write files: removed, with what the test wrote, when the
//! test ends (also when it fails).

use std::path::Path;

/// A fresh directory under the system's temp directory, named `arps-{tag}-` and a random suffix;
/// removed with its contents when dropped. It derefs to its path.
pub struct Scratch(tempfile::TempDir);

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        self.0.path()
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        self.0.path()
    }
}

/// A new [`Scratch`] directory named after `tag`.
pub fn scratch(tag: &str) -> Scratch {
    Scratch(tempfile::Builder::new().prefix(&format!("arps-{tag}-")).tempdir().expect("a scratch directory"))
}
