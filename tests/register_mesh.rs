//! A scan registered onto a CAD model: the model's STL read as its surface
//! (`ReadOptions::surface_points`) recovers a known motion, in any pose. (Its vertices, the
//! default reading, sit on the part's edges and corners: a scan of its faces has few of them
//! within reach.)

use arps::io::{read_mesh, read_point_cloud_with, ReadOptions};
use arps::transform::{euler_xyz, from_rotation_translation, rigid_inverse, rotation_error_deg};
use arps::{Options, PointCloud, Registrar};
use nalgebra::Vector3;

#[test]
fn a_partial_scan_registers_onto_a_cad_model_read_as_its_surface() {
    let name = "angle_block_binary_solid.stl";
    let bytes = std::fs::read(format!("{}/fixtures/formats/{name}", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let model = read_point_cloud_with(&bytes, name, &ReadOptions { surface_points: Some(20_000), seed: 0 }).unwrap();
    // the scan: other points of the same surface, the part seen from one side (70% of it)
    let dense = read_mesh(&bytes, name).unwrap().sample_surface(20_000, 7).unwrap();
    let (lo, hi) = dense.bounds();
    let cut = lo[0] + 0.3 * (hi[0] - lo[0]);
    let seen = PointCloud::new(dense.points.iter().copied().filter(|p| p[0] > cut).collect());
    let mut registrar = Registrar::with_default_model().unwrap();
    for (degrees, shift) in [([10.0, -20.0, 30.0], [0.5, 0.2, -0.3]), ([120.0, 40.0, -70.0], [1.0, 0.0, 0.5])] {
        let [a, b, c] = degrees.map(f64::to_radians);
        let gt = from_rotation_translation(&euler_xyz(a, b, c), &Vector3::from(shift));
        let scan = seen.transformed(&rigid_inverse(&gt));
        let r = registrar.register(&scan, &model, &Options::default()).unwrap();
        let rot = rotation_error_deg(&r.T_target_source, &gt);
        let trans = (r.T_target_source.fixed_view::<3, 1>(0, 3) - gt.fixed_view::<3, 1>(0, 3)).norm();
        assert!(rot < 1.0 && trans < 0.01, "{degrees:?}: {rot:.2} deg, {trans:.4} off (the part is about 1.3 across)");
        assert!(r.confidence >= 0.5, "{degrees:?}: confidence {}", r.confidence);
    }
}
