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
    let model = read_point_cloud_with(
        &bytes,
        name,
        &ReadOptions { surface_points: Some(20_000), seed: 0, scan: None, classes: None, min_opacity: None },
    )
    .unwrap();
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

/// The measurement behind `BENCHMARK.md`, "Meshes read as their surface": every mesh of a
/// directory (`ARPS_MESH_DIR`, default `../shared/data/meshes`, searched recursively; skipped when
/// absent) as the target, read as its vertices and as 50,000 points over its surface; the source
/// a scan of it: 20,000 points of its surface, the 70% on one side of a random plane, noise of
/// 0.5% of its size, turned by any rotation and moved. Prints the recall (rotation error below
/// 15 degrees and translation error below 0.2 of the mesh's half-extent), the median confidence
/// and the median time of each reading. `cargo test --release --test register_mesh -- --ignored
/// --nocapture`.
#[test]
#[ignore]
fn mesh_targets_read_as_vertices_and_as_surfaces() {
    /// Right answers, confidences, milliseconds and the wrong answers' confidences of one reading
    /// on one group of meshes.
    type Tally = (usize, Vec<f64>, Vec<f64>, Vec<f64>);
    use rand::Rng;
    let dir = std::env::var("ARPS_MESH_DIR").unwrap_or_else(|_| "../shared/data/meshes".into());
    let mut files = Vec::new();
    let mut stack = vec![std::path::PathBuf::from(&dir)];
    while let Some(d) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else { continue };
        for e in entries.flatten() {
            let p = e.path();
            let ext = p.extension().map(|x| x.to_string_lossy().to_lowercase()).unwrap_or_default();
            if p.is_dir() {
                stack.push(p);
            } else if ["obj", "off", "ply", "stl"].contains(&ext.as_str()) {
                files.push(p);
            }
        }
    }
    files.sort();
    if files.is_empty() {
        eprintln!("no meshes under {dir}: skipped");
        return;
    }
    let mut registrar = Registrar::with_default_model().unwrap();
    // per group (all, fewer than 5,000 vertices) and reading
    let mut tally: [[Tally; 2]; 2] = Default::default();
    let mut used = [0; 2];
    for (k, path) in files.iter().enumerate() {
        let bytes = std::fs::read(path).unwrap();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let Ok(mesh) = read_mesh(&bytes, &name) else { continue };
        let Ok(dense) = mesh.sample_surface(20_000, k as u64) else { continue };
        let (lo, hi) = dense.bounds();
        let half = (0..3).map(|a| (hi[a] - lo[a]) as f64 / 2.0).fold(0.0, f64::max);
        let center = Vector3::from_fn(|a, _| (lo[a] + hi[a]) as f64 / 2.0);
        let mut rng = arps::sampling::rng(1000 + k as u64);
        let (z, phi): (f64, f64) = (rng.random_range(-1.0..1.0), rng.random_range(0.0..std::f64::consts::TAU));
        let dir = Vector3::new((1.0 - z * z).sqrt() * phi.cos(), (1.0 - z * z).sqrt() * phi.sin(), z);
        let mut along: Vec<f64> =
            dense.points.iter().map(|p| (Vector3::from(p.map(|v| v as f64)) - center).dot(&dir)).collect();
        along.sort_by(f64::total_cmp);
        let cut = along[along.len() * 3 / 10];
        let seen: Vec<[f32; 3]> = dense
            .points
            .iter()
            .filter(|p| (Vector3::from(p.map(|v| v as f64)) - center).dot(&dir) >= cut)
            .map(|p| {
                // Box-Muller: a standard normal per coordinate
                p.map(|v| {
                    let (u1, u2): (f64, f64) = (rng.random_range(f64::EPSILON..1.0), rng.random());
                    let n = (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos();
                    v + (0.005 * half * n) as f32
                })
            })
            .collect();
        let angles = [0; 3].map(|_| rng.random_range(-180.0f64..180.0).to_radians());
        let shift = Vector3::from_fn(|_, _| rng.random_range(-0.5..0.5) * half);
        let gt = from_rotation_translation(&euler_xyz(angles[0], angles[1], angles[2]), &shift);
        let scan = PointCloud::new(seen).transformed(&rigid_inverse(&gt));
        let readings = [None, Some(50_000)];
        let targets: Vec<_> = readings
            .iter()
            .map(|&n| {
                read_point_cloud_with(
                    &bytes,
                    &name,
                    &ReadOptions { surface_points: n, seed: 0, scan: None, classes: None, min_opacity: None },
                )
            })
            .collect();
        if targets.iter().any(|t| t.is_err()) {
            continue;
        }
        let groups: &[usize] = if mesh.vertices.len() < 5000 { &[0, 1] } else { &[0] };
        for (reading, target) in targets.into_iter().enumerate() {
            let t0 = std::time::Instant::now();
            let r = registrar.register(&scan, &target.unwrap(), &Options::default());
            let ms = t0.elapsed().as_secs_f64() * 1e3;
            let (right, confidence) = match r {
                Ok(r) => {
                    let trans = (r.T_target_source.fixed_view::<3, 1>(0, 3) - gt.fixed_view::<3, 1>(0, 3)).norm();
                    (rotation_error_deg(&r.T_target_source, &gt) < 15.0 && trans < 0.2 * half, r.confidence)
                }
                Err(_) => (false, 0.0),
            };
            for &g in groups {
                let slot = &mut tally[g][reading];
                slot.0 += usize::from(right);
                slot.1.push(confidence);
                slot.2.push(ms);
                if !right {
                    slot.3.push(confidence);
                }
            }
        }
        for &g in groups {
            used[g] += 1;
        }
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
    };
    for (group, (n, readings)) in
        ["all meshes", "meshes of fewer than 5,000 vertices"].iter().zip(used.iter().zip(tally.iter_mut()))
    {
        println!("{group} under {dir}: {n}");
        for (what, (right, conf, ms, wrong)) in ["vertices", "surface, 50,000 points"].iter().zip(readings.iter_mut()) {
            let doubted = wrong.iter().filter(|&&c| c < 0.5).count();
            println!(
                "  target read as its {what}: recall {:.3} ({right} of {n}), median confidence {:.2}, median {:.1} ms; \
                 wrong answers with confidence below 0.5: {doubted} of {}",
                *right as f64 / *n as f64,
                median(conf),
                median(ms),
                wrong.len()
            );
        }
    }
}
