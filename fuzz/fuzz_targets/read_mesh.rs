//! Mesh formats (the first byte picks the name); a mesh that reads is also measured and sampled.
#![no_main]

use libfuzzer_sys::fuzz_target;

const NAMES: [&str; 5] = ["a.ply", "a.obj", "a.off", "a.stl", "no_extension"];

fuzz_target!(|data: &[u8]| {
    let Some((&choice, bytes)) = data.split_first() else { return };
    let name = NAMES[choice as usize % NAMES.len()];
    if let Ok(mesh) = arps::io::read_mesh(bytes, name) {
        // Readers only produce in-range indices.
        let n = mesh.vertices.len();
        assert!(mesh.triangles.iter().flatten().all(|&i| (i as usize) < n));
        let _ = mesh.surface_area();
        if let Ok(s) = mesh.sample_surface(8, u64::from(choice)) {
            assert_eq!(s.len(), 8);
        }
    }
});
