//! Any bytes, under any of the supported file names (the first byte picks the name), must give
//! a cloud or an error: never a panic, never a huge allocation.
#![no_main]

use libfuzzer_sys::fuzz_target;

const NAMES: [&str; 13] = [
    "a.ply", "a.pcd", "a.xyz", "a.pts", "a.csv", "a.obj", "a.off", "a.stl", "a.txt", "no_extension", "a.las", "a.laz", "a.e57",
];

fuzz_target!(|data: &[u8]| {
    let Some((&choice, bytes)) = data.split_first() else { return };
    let name = NAMES[choice as usize % NAMES.len()];
    if let Ok(cloud) = arps::io::read_point_cloud(bytes, name) {
        // Whatever was read writes and reads back (bit-identically near zero).
        assert!(reads_back(&cloud));
    }
});

include!("../same_points.rs");

