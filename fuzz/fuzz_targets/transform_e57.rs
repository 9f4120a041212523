//! Any bytes, made into E57 pages with valid checksums (`e57_pages.rs`), moved by a fixed rigid
//! motion (`io::transform_file` on an E57 file: the scans' poses rewritten in a new XML
//! section), whole or one scan alone (`io::transform_file_with`, a file of that scan): a moved
//! file or an error, never a panic. A moved file of a file the reader reads reads too, to as
//! many points (a scan alone: or fails at its end, see below).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let bytes = e57_pages(data);
    let turn = nalgebra::Rotation3::from_euler_angles(0.3, -1.1, 2.0).to_homogeneous();
    let m = nalgebra::Matrix4::new_translation(&nalgebra::Vector3::new(1.5, -2.0, 0.25)) * turn;
    // the whole file, and each of its first two scans alone (a file of its own)
    for scan in [None, Some(0), Some(1)] {
        let options = arps::io::ReadOptions { scan, ..Default::default() };
        if let Ok(moved) = arps::io::transform_file_with(&bytes, "a.e57", &m, &options) {
            if let Ok(before) = arps::io::read_point_cloud_with(&bytes, "a.e57", &options) {
                let after = arps::io::read_point_cloud(&moved, "a.e57");
                match (scan, after) {
                    (_, Ok(after)) => assert_eq!(before.len(), after.len()),
                    // a scan alone is its file's last section: one whose packets fall short of
                    // its records, which the original's reader filled from the bytes after it,
                    // meets the file's end
                    (Some(_), Err(_)) => {}
                    (None, Err(e)) => panic!("a moved file reads: {e}"),
                }
            }
        }
    }
});

include!("../e57_pages.rs");
