//! A bank of real meshes read from a directory (OBJ/OFF/PLY/STL, recursively), with degenerate
//! meshes skipped for a stated reason, and a deterministic train/validation split by shape.

use super::source::Split;
use crate::io::{self, Mesh};
use std::path::{Path, PathBuf};

/// The fewest triangles a bank mesh may have.
pub const MIN_TRIANGLES: usize = 4;
/// A mesh is "flat" (skipped) when its smallest bounding-box extent is below this fraction of
/// the largest.
pub const FLAT_RATIO: f64 = 0.01;

/// A mesh with a name: the path relative to the bank directory, `/`-separated.
#[derive(Clone, Debug)]
pub struct NamedMesh {
    /// Relative path, e.g. `libigl/bunny.off`.
    pub name: String,
    /// The mesh as read.
    pub mesh: Mesh,
}

/// A mesh file that was not used, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct Skipped {
    /// Relative path.
    pub name: String,
    /// Why (unreadable, no area, too few triangles, flat, non-finite).
    pub reason: String,
}

/// The meshes of a directory.
#[derive(Clone, Debug, Default)]
pub struct Bank {
    /// Usable meshes, sorted by name.
    pub meshes: Vec<NamedMesh>,
    /// Files with a mesh extension that were skipped, sorted by name. The library does not print;
    /// callers log these (the CLI prints one line each on stderr).
    pub skipped: Vec<Skipped>,
}

/// Why a mesh is unusable for sampling pairs, or `Ok`.
pub fn check_mesh(mesh: &Mesh) -> Result<(), String> {
    if mesh.triangles.len() < MIN_TRIANGLES {
        return Err(format!("too few triangles ({} < {MIN_TRIANGLES})", mesh.triangles.len()));
    }
    let nv = mesh.vertices.len();
    if let Some(t) = mesh.triangles.iter().find(|t| t.iter().any(|&i| i as usize >= nv)) {
        return Err(format!("triangle {t:?} refers beyond the {nv} vertices"));
    }
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for t in &mesh.triangles {
        for &i in t {
            let p = mesh.vertices[i as usize];
            if !p.iter().all(|v| v.is_finite()) {
                return Err(format!("vertex {i} is not finite: {p:?}"));
            }
            for a in 0..3 {
                lo[a] = lo[a].min(p[a] as f64);
                hi[a] = hi[a].max(p[a] as f64);
            }
        }
    }
    let area = mesh.surface_area();
    if !(area > 0.0 && area.is_finite()) {
        return Err(format!("no surface area ({area})"));
    }
    let ext: Vec<f64> = (0..3).map(|a| hi[a] - lo[a]).collect();
    let max = ext.iter().copied().fold(0.0, f64::max);
    let min = ext.iter().copied().fold(f64::INFINITY, f64::min);
    if min.is_nan() || min < FLAT_RATIO * max {
        return Err(format!(
            "flat: bounding box {:.3} x {:.3} x {:.3}, smallest extent below {}% of the largest",
            ext[0],
            ext[1],
            ext[2],
            FLAT_RATIO * 100.0
        ));
    }
    Ok(())
}

fn is_mesh_file(p: &Path) -> bool {
    p.extension()
        .and_then(|e| e.to_str())
        .map(|e| matches!(e.to_ascii_lowercase().as_str(), "obj" | "off" | "ply" | "stl"))
        .unwrap_or(false)
}

fn walk(dir: &Path, out: &mut Vec<PathBuf>) -> std::io::Result<()> {
    let mut entries: Vec<_> = std::fs::read_dir(dir)?.collect::<Result<_, _>>()?;
    entries.sort_by_key(|e| e.file_name());
    for e in entries {
        let p = e.path();
        let ft = e.file_type()?;
        if ft.is_dir() {
            walk(&p, out)?;
        } else if is_mesh_file(&p) {
            out.push(p);
        }
    }
    Ok(())
}

/// Reads every OBJ/OFF/PLY/STL file under `dir` (recursively, in sorted order) with
/// [`io::read_mesh`]; unreadable and degenerate meshes ([`check_mesh`]) go to
/// [`Bank::skipped`]. Fails only if `dir` itself cannot be listed.
pub fn load_dir(dir: &Path) -> std::io::Result<Bank> {
    let mut files = Vec::new();
    walk(dir, &mut files)?;
    let mut bank = Bank::default();
    for path in files {
        let name = path
            .strip_prefix(dir)
            .unwrap_or(&path)
            .components()
            .map(|c| c.as_os_str().to_string_lossy().into_owned())
            .collect::<Vec<_>>()
            .join("/");
        let file_name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let read = std::fs::read(&path).map_err(|e| e.to_string()).and_then(|bytes| {
            // the readers are new; a panic in one must not take the whole bank down
            std::panic::catch_unwind(|| io::read_mesh(&bytes, &file_name))
                .map_err(|_| "the reader panicked".to_string())?
                .map_err(|e| e.to_string())
        });
        match read.and_then(|m| check_mesh(&m).map(|()| m)) {
            Ok(mesh) => bank.meshes.push(NamedMesh { name, mesh }),
            Err(reason) => bank.skipped.push(Skipped { name, reason }),
        }
    }
    Ok(bank)
}

/// The split a bank shape belongs to: validation when the FNV-1a hash of its name (relative
/// path), scaled to [0, 1), is below `val_fraction`. Deterministic and independent of what else
/// is in the bank.
pub fn split_of(name: &str, val_fraction: f64) -> Split {
    let u = super::unit_of_hash(super::fnv1a(name));
    if u < val_fraction {
        Split::Val
    } else {
        Split::Train
    }
}

impl Bank {
    /// The meshes of one split ([`split_of`]).
    pub fn split(&self, split: Split, val_fraction: f64) -> Vec<&NamedMesh> {
        self.meshes.iter().filter(|m| split_of(&m.name, val_fraction) == split).collect()
    }

    /// One line per skipped file (`name: reason`), for logging.
    pub fn skipped_report(&self) -> String {
        self.skipped.iter().map(|s| format!("skipped {}: {}\n", s.name, s.reason)).collect()
    }
}
