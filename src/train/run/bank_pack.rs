//! The shape bank in one compact file (`*.arpsbank.gz`), for machines the bank directory does not
//! reach: the usable meshes exactly as [`crate::data::bank::load_dir`] read them (names,
//! vertices, triangles) and the skipped files with their reasons, gzipped. A run whose `bank` is
//! such a file gets the same shapes, the same split and the same pairs as with the directory.
//!
//! Layout (inside the gzip stream, little-endian): the 8 bytes [`MAGIC`], a `u32` JSON length,
//! JSON `{"version": 1, "meshes": [{"name", "vertices", "triangles"}], "skipped": [{"name",
//! "reason"}]}` (counts), then per mesh its vertices (`f32 x 3`) and triangles (`u32 x 3`).

use crate::data::bank::{Bank, NamedMesh, Skipped};
use crate::io::Mesh;
use serde::{Deserialize, Serialize};
use std::io::{Read, Write};
use std::path::Path;

/// First bytes of the (decompressed) pack.
pub const MAGIC: &[u8; 8] = b"ARPSBANK";
/// Layout version.
pub const VERSION: u32 = 1;
/// The most vertices or triangles one packed mesh may claim (a corrupt count cannot allocate
/// without limit).
const MAX_ITEMS: usize = 1 << 26;

#[derive(Serialize, Deserialize)]
struct MeshEntry {
    name: String,
    vertices: usize,
    triangles: usize,
}

#[derive(Serialize, Deserialize)]
struct SkippedEntry {
    name: String,
    reason: String,
}

#[derive(Serialize, Deserialize)]
struct Index {
    version: u32,
    meshes: Vec<MeshEntry>,
    skipped: Vec<SkippedEntry>,
}

/// Whether `path` names a packed bank (a file) rather than a bank directory.
pub fn is_pack(path: &Path) -> bool {
    path.is_file()
}

/// Writes `bank` packed and gzipped.
pub fn write(bank: &Bank, out: &mut impl Write) -> std::io::Result<()> {
    let index = Index {
        version: VERSION,
        meshes: bank
            .meshes
            .iter()
            .map(|m| MeshEntry {
                name: m.name.clone(),
                vertices: m.mesh.vertices.len(),
                triangles: m.mesh.triangles.len(),
            })
            .collect(),
        skipped: bank.skipped.iter().map(|s| SkippedEntry { name: s.name.clone(), reason: s.reason.clone() }).collect(),
    };
    let json = serde_json::to_vec(&index).map_err(std::io::Error::other)?;
    let mut gz = flate2::write::GzEncoder::new(out, flate2::Compression::best());
    gz.write_all(MAGIC)?;
    gz.write_all(&(json.len() as u32).to_le_bytes())?;
    gz.write_all(&json)?;
    let mut buf = Vec::new();
    for m in &bank.meshes {
        buf.clear();
        for v in m.mesh.vertices.iter().flatten() {
            buf.extend_from_slice(&v.to_le_bytes());
        }
        for t in m.mesh.triangles.iter().flatten() {
            buf.extend_from_slice(&t.to_le_bytes());
        }
        gz.write_all(&buf)?;
    }
    gz.finish()?;
    Ok(())
}

/// Reads a packed bank.
pub fn read(input: impl Read) -> Result<Bank, String> {
    let mut r = flate2::read::GzDecoder::new(input);
    let bad = |e: std::io::Error| format!("packed bank: {e}");
    let mut magic = [0u8; 8];
    r.read_exact(&mut magic).map_err(bad)?;
    if &magic != MAGIC {
        return Err("not a packed arps bank (bad magic)".into());
    }
    let mut len = [0u8; 4];
    r.read_exact(&mut len).map_err(bad)?;
    let len = u32::from_le_bytes(len) as usize;
    if len > MAX_ITEMS {
        return Err(format!("packed bank index of {len} bytes is too long"));
    }
    let mut json = vec![0u8; len];
    r.read_exact(&mut json).map_err(bad)?;
    let index: Index = serde_json::from_slice(&json).map_err(|e| format!("packed bank index: {e}"))?;
    if index.version != VERSION {
        return Err(format!("packed bank version {} (this build reads {VERSION})", index.version));
    }
    let mut bank = Bank::default();
    for e in index.meshes {
        if e.vertices > MAX_ITEMS || e.triangles > MAX_ITEMS {
            return Err(format!("packed bank mesh {} is too large", e.name));
        }
        let mut v = vec![0u8; e.vertices * 12];
        r.read_exact(&mut v).map_err(bad)?;
        let mut t = vec![0u8; e.triangles * 12];
        r.read_exact(&mut t).map_err(bad)?;
        let f = |c: &[u8]| f32::from_le_bytes([c[0], c[1], c[2], c[3]]);
        let u = |c: &[u8]| u32::from_le_bytes([c[0], c[1], c[2], c[3]]);
        let vertices = v.chunks_exact(12).map(|c| [f(&c[0..4]), f(&c[4..8]), f(&c[8..12])]).collect();
        let triangles = t.chunks_exact(12).map(|c| [u(&c[0..4]), u(&c[4..8]), u(&c[8..12])]).collect();
        let mesh = Mesh { vertices, triangles };
        crate::data::bank::check_mesh(&mesh).map_err(|why| format!("packed bank mesh {}: {why}", e.name))?;
        bank.meshes.push(NamedMesh { name: e.name, mesh });
    }
    bank.skipped = index.skipped.into_iter().map(|s| Skipped { name: s.name, reason: s.reason }).collect();
    Ok(bank)
}

/// Loads a bank from a directory or a packed file.
pub fn load(path: &Path) -> Result<Bank, String> {
    if is_pack(path) {
        read(std::fs::File::open(path).map_err(|e| format!("{}: {e}", path.display()))?)
    } else {
        crate::data::bank::load_dir(path).map_err(|e| e.to_string())
    }
}
