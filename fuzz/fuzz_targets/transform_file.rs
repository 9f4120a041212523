//! Any bytes as a file of each format `io::transform_file` moves (the first byte picks the
//! extension; its top bit a change of unit), moved by a fixed rigid motion: a moved file or an error, never a panic, never an
//! allocation beyond the input's size. A moved file of a file the reader reads reads too, to as
//! many points (STL: as many facets).
#![no_main]

use libfuzzer_sys::fuzz_target;

const NAMES: [&str; 9] = ["a.pcd", "a.xyz", "a.csv", "a.pts", "a.obj", "a.stl", "a.ply", "a.las", "a.off"];

fuzz_target!(|data: &[u8]| {
    let Some((&pick, bytes)) = data.split_first() else { return };
    let name = NAMES[(pick & 0x7f) as usize % NAMES.len()];
    let turn = nalgebra::Rotation3::from_euler_angles(0.3, -1.1, 2.0).to_homogeneous();
    let m = nalgebra::Matrix4::new_translation(&nalgebra::Vector3::new(1.5, -2.0, 0.25)) * turn;
    let m = if pick >= 128 { m * nalgebra::Matrix4::new_scaling(1000.0) } else { m };
    if let Ok(moved) = arps::io::transform_file(bytes, name, &m) {
        if name.ends_with(".stl") {
            // STL's corners are welded by position, and two a bit apart may round to one once
            // moved: the facets are what must all be there.
            if let Ok(before) = arps::io::read_mesh(bytes, name) {
                let after = arps::io::read_mesh(&moved, name).expect("a moved file reads");
                assert_eq!(before.triangles.len(), after.triangles.len());
            }
        } else if let Ok(before) = arps::io::read_point_cloud(bytes, name) {
            let after = arps::io::read_point_cloud(&moved, name).expect("a moved file reads");
            assert_eq!(before.len(), after.len());
        }
    }
});
