//! Any bytes as a LAS file, moved by a fixed rigid motion (`io::transform_las`): a moved file or
//! an error, never a panic, never an allocation beyond the input's size. A moved file of a file
//! the reader reads reads too, to as many points, each where the motion puts it (to the scale).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let turn = nalgebra::Rotation3::from_euler_angles(0.3, -1.1, 2.0).to_homogeneous();
    let m = nalgebra::Matrix4::new_translation(&nalgebra::Vector3::new(1.5, -2.0, 0.25)) * turn;
    if let Ok(moved) = arps::io::transform_las(data, &m) {
        if let Ok(before) = arps::io::read_point_cloud(data, "a.las") {
            let after = arps::io::read_point_cloud(&moved, "a.las").expect("a moved file reads");
            assert_eq!(before.len(), after.len());
        }
    }
});
