//! Reads every file of the shared data directories when they exist (they are not part of a
//! fresh clone; the test then does nothing). Looked for in `ARPS_SHARED_DATA`, `../shared/data`
//! beside the crate, then `/work/shared/data`.

use std::path::{Path, PathBuf};

fn shared_root() -> Option<PathBuf> {
    let beside = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data");
    let candidates = [
        std::env::var_os("ARPS_SHARED_DATA").map(PathBuf::from),
        Some(beside),
        Some(PathBuf::from("/work/shared/data")),
    ];
    candidates.into_iter().flatten().find(|p| p.join("formats").is_dir())
}

fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(rd) = std::fs::read_dir(dir) else { return };
    for e in rd.flatten() {
        let p = e.path();
        if p.is_dir() {
            files(&p, out);
        } else if arps::io::Format::from_file_name(&p.file_name().unwrap().to_string_lossy()).is_some() {
            out.push(p);
        }
    }
}

#[test]
fn every_shared_file_reads() {
    let Some(root) = shared_root() else {
        eprintln!("shared data not present: skipped");
        return;
    };
    let mut all = Vec::new();
    files(&root.join("formats"), &mut all);
    files(&root.join("meshes"), &mut all);
    all.sort();
    let mut failures = Vec::new();
    for p in &all {
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        let bytes = std::fs::read(p).unwrap();
        let format = arps::io::detect_format(&bytes, &name).unwrap();
        match arps::io::read_point_cloud(&bytes, &name) {
            Ok(c) => {
                let nan = c.points.iter().filter(|p| p.iter().any(|v| !v.is_finite())).count();
                let mesh = if format.has_faces() {
                    match arps::io::read_mesh(&bytes, &name) {
                        Ok(m) => format!("{} triangles, area {:.4}", m.triangles.len(), m.surface_area()),
                        Err(e) => {
                            failures.push(format!("{}: mesh: {e}", p.display()));
                            String::new()
                        }
                    }
                } else {
                    String::new()
                };
                eprintln!("{:?} {}: {} points ({nan} non-finite) {mesh}", format, p.display(), c.len());
            }
            Err(e) => failures.push(format!("{}: {e}", p.display())),
        }
        // Sniffing agrees with the extension.
        if let Ok(sniffed) = arps::io::detect_format(&bytes, "noext") {
            if sniffed != format && !(format == arps::io::Format::Xyz) {
                failures.push(format!("{}: sniffed as {sniffed:?}, extension says {format:?}", p.display()));
            }
        } else {
            failures.push(format!("{}: could not sniff", p.display()));
        }
    }
    // Known-bad inputs: a scan without faces, and assimp's deliberately truncated ant-half.ply.
    let expected = [
        "bun000.ply: mesh: PLY parse error: the file has no 'face' element",
        "ant-half.ply: mesh: PLY parse error: the file ends after 259 of the 912 'face' lines",
    ];
    failures.retain(|f| !expected.iter().any(|e| f.contains(e)));
    assert!(failures.is_empty(), "{} failures:\n{}", failures.len(), failures.join("\n"));
}
