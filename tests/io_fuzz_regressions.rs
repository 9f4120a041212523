//! Replays the fuzz seeds (which must all read) and every input the fuzzers found crashing
//! (`fuzz/regressions/<target>/`, which must now give a result or an error without panicking),
//! through the same code as the fuzz targets in `fuzz/fuzz_targets/` (the movers' seeds must
//! move, their regressions fail cleanly). The `register_clouds`
//! seeds and regressions go through that target's own body (`fuzz/register_clouds.rs`): each
//! must register or fail cleanly, with a finite, rigid answer, a fitness and a confidence in
//! [0, 1], the same answer twice, and a usable registrar after an error.

use std::path::Path;

const PC_NAMES: [&str; 13] = [
    "a.ply",
    "a.pcd",
    "a.xyz",
    "a.pts",
    "a.csv",
    "a.obj",
    "a.off",
    "a.stl",
    "a.txt",
    "no_extension",
    "a.las",
    "a.laz",
    "a.e57",
];
const MESH_NAMES: [&str; 5] = ["a.ply", "a.obj", "a.off", "a.stl", "no_extension"];

fn inputs(dir: &str) -> Vec<(String, Vec<u8>)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz").join(dir);
    let Ok(rd) = std::fs::read_dir(&dir) else { return Vec::new() };
    let mut v: Vec<_> = rd
        .flatten()
        .map(|e| (e.file_name().to_string_lossy().into_owned(), std::fs::read(e.path()).unwrap()))
        .collect();
    v.sort();
    v
}

/// The `read_point_cloud` fuzz target's body; `Ok(points)` or the error text.
fn point_cloud_target(data: &[u8]) -> Result<usize, String> {
    let Some((&choice, bytes)) = data.split_first() else { return Err("empty".into()) };
    let name = PC_NAMES[choice as usize % PC_NAMES.len()];
    let cloud = arps::io::read_point_cloud(bytes, name).map_err(|e| e.to_string())?;
    assert!(reads_back(&cloud));
    Ok(cloud.len())
}

include!("../fuzz/same_points.rs");
include!("../fuzz/e57_pages.rs");

/// The `read_e57` fuzz target's body: the bytes made into pages with valid checksums.
fn e57_target(data: &[u8]) -> Result<usize, String> {
    let bytes = e57_pages(data);
    let cloud = arps::io::read_point_cloud(&bytes, "a.e57").map_err(|e| e.to_string())?;
    assert!(reads_back(&cloud));
    Ok(cloud.len())
}

#[test]
fn e57_seeds_read_and_regressions_do_not_panic() {
    let seeds = inputs("seeds/read_e57");
    assert!(seeds.len() >= 2);
    for (name, data) in seeds {
        // real files: their pages' checksums are already what the harness writes
        assert_eq!(e57_pages(&data), data, "seed {name}: the harness rewrote a valid page");
        let n = e57_target(&data).unwrap_or_else(|e| panic!("seed {name}: {e}"));
        assert!(n >= 100, "seed {name}: {n} points");
    }
    for (name, data) in inputs("regressions/read_e57") {
        let r = e57_target(&data);
        eprintln!("read_e57 {name}: {r:?}");
    }
}

fn mesh_target(data: &[u8]) -> Result<usize, String> {
    let Some((&choice, bytes)) = data.split_first() else { return Err("empty".into()) };
    let name = MESH_NAMES[choice as usize % MESH_NAMES.len()];
    let mesh = arps::io::read_mesh(bytes, name).map_err(|e| e.to_string())?;
    let n = mesh.vertices.len();
    assert!(mesh.triangles.iter().flatten().all(|&i| (i as usize) < n));
    let _ = mesh.surface_area();
    if let Ok(s) = mesh.sample_surface(8, u64::from(choice)) {
        assert_eq!(s.len(), 8);
    }
    Ok(mesh.triangles.len())
}

include!("../fuzz/gltf_target.rs");

#[test]
fn gltf_seeds_read_and_regressions_do_not_panic() {
    let seeds = inputs("seeds/read_gltf");
    assert!(seeds.len() >= 7);
    for (name, data) in seeds {
        let r = gltf_target(&data);
        match name.as_str() {
            "draco" => assert!(r.unwrap_err().contains("KHR_draco_mesh_compression")),
            "instanced" => assert_eq!(r, Ok(12), "three instances"),
            _ => assert_eq!(r, Ok(4), "seed {name}"),
        }
    }
    for (name, data) in inputs("regressions/read_gltf") {
        let r = gltf_target(&data);
        eprintln!("read_gltf {name}: {r:?}");
    }
}

#[test]
fn seeds_read() {
    let seeds = inputs("seeds/read_point_cloud");
    assert!(seeds.len() >= 20);
    for (name, data) in seeds {
        let n = point_cloud_target(&data).unwrap_or_else(|e| panic!("seed {name}: {e}"));
        assert!(n >= 4, "seed {name}: {n} points");
    }
    for (name, data) in inputs("seeds/read_mesh") {
        assert_eq!(mesh_target(&data).unwrap_or_else(|e| panic!("seed {name}: {e}")), 4, "seed {name}");
    }
}

/// The fixed motion of the `transform_las` and `transform_file` fuzz targets (the latter scaled
/// by 1000 when the first byte is 128 or more).
fn fuzz_motion(scaled: bool) -> nalgebra::Matrix4<f64> {
    let turn = nalgebra::Rotation3::from_euler_angles(0.3, -1.1, 2.0).to_homogeneous();
    let m = nalgebra::Matrix4::new_translation(&nalgebra::Vector3::new(1.5, -2.0, 0.25)) * turn;
    if scaled {
        m * nalgebra::Matrix4::new_scaling(1000.0)
    } else {
        m
    }
}

#[test]
fn transform_seeds_move_and_regressions_fail_cleanly() {
    // every seed moves, and reads back to as many points (STL: facets)
    for (name, data) in inputs("seeds/transform_las") {
        let moved = arps::io::transform_las(&data, &fuzz_motion(false)).unwrap_or_else(|e| panic!("seed {name}: {e}"));
        let (a, b) =
            (arps::io::read_point_cloud(&data, "a.las").unwrap(), arps::io::read_point_cloud(&moved, "a.las").unwrap());
        assert_eq!(a.len(), b.len(), "seed {name}");
    }
    const NAMES: [&str; 9] = ["a.pcd", "a.xyz", "a.csv", "a.pts", "a.obj", "a.stl", "a.ply", "a.las", "a.off"];
    let seeds = inputs("seeds/transform_file");
    assert!(seeds.len() >= 10);
    for (name, data) in seeds {
        let (&pick, bytes) = data.split_first().unwrap();
        let file = NAMES[(pick & 0x7f) as usize % NAMES.len()];
        let moved = arps::io::transform_file(bytes, file, &fuzz_motion(pick >= 128))
            .unwrap_or_else(|e| panic!("seed {name} ({file}): {e}"));
        let count = |b: &[u8]| match file {
            "a.stl" => arps::io::read_mesh(b, file).unwrap().triangles.len(),
            _ => arps::io::read_point_cloud(b, file).unwrap().len(),
        };
        assert_eq!(count(bytes), count(&moved), "seed {name}");
    }
    for (name, data) in inputs("seeds/transform_e57") {
        let bytes = e57_pages(&data);
        // the whole file, and its first scan alone
        for scan in [None, Some(0)] {
            let options = arps::io::ReadOptions { scan, ..Default::default() };
            let moved = arps::io::transform_file_with(&bytes, "a.e57", &fuzz_motion(false), &options)
                .unwrap_or_else(|e| panic!("seed {name}: {e}"));
            let (a, b) = (
                arps::io::read_point_cloud_with(&bytes, "a.e57", &options).unwrap(),
                arps::io::read_point_cloud(&moved, "a.e57").unwrap(),
            );
            assert_eq!(a.len(), b.len(), "seed {name}, scan {scan:?}");
        }
    }
    // a scan whose packets fall short of its records (a reader goes on past its section): alone,
    // a file that fails to read at its end, not one that reads other bytes as points
    for (name, data) in inputs("regressions/transform_e57") {
        let bytes = e57_pages(&data);
        let scan = arps::io::ReadOptions { scan: Some(0), ..Default::default() };
        let moved = arps::io::transform_file_with(&bytes, "a.e57", &fuzz_motion(false), &scan).unwrap();
        let e = arps::io::read_point_cloud(&moved, "a.e57").unwrap_err().to_string();
        assert!(e.contains("E57") && e.contains("fill whole buffer"), "{name}: {e}");
    }
    // a LAZ file whose NIR layer claims 1.8 GB: refused before the layer is read
    for (name, data) in inputs("regressions/transform_las") {
        let r = arps::io::transform_las(&data, &fuzz_motion(false));
        eprintln!("transform_las {name}: {:?}", r.as_ref().map(|b| b.len()));
        assert!(r.is_err(), "{name}");
    }
}

#[test]
fn crash_regressions_do_not_panic() {
    for (name, data) in inputs("regressions/read_point_cloud") {
        let r = point_cloud_target(&data);
        eprintln!("read_point_cloud {name}: {r:?}");
    }
    for (name, data) in inputs("regressions/read_mesh") {
        let r = mesh_target(&data);
        eprintln!("read_mesh {name}: {r:?}");
    }
}

#[test]
fn option_and_config_seeds_parse_and_run() {
    let seeds = inputs("seeds/options_json");
    assert!(seeds.len() >= 5);
    let mut reg = arps::Registrar::new(&arps::Weights::random(&arps::ModelConfig::tiny(), 0).unwrap()).unwrap();
    let cloud = |k: f32| {
        arps::PointCloud::new(
            (0..200).map(|i| [(i % 10) as f32 * 0.1 + k, (i / 10 % 10) as f32 * 0.1, (i / 100) as f32 * 0.3]).collect(),
        )
    };
    for (name, data) in seeds {
        let options: arps::Options = serde_json::from_slice(&data).unwrap_or_else(|e| panic!("seed {name}: {e}"));
        reg.register(&cloud(0.0), &cloud(0.01), &options).unwrap_or_else(|e| panic!("seed {name}: {e}"));
    }
    let seeds = inputs("seeds/model_config");
    assert!(seeds.len() >= 3);
    for (name, data) in seeds {
        let config: arps::ModelConfig = serde_json::from_slice(&data).unwrap_or_else(|e| panic!("seed {name}: {e}"));
        config.validate().unwrap_or_else(|e| panic!("seed {name}: {e}"));
    }
}

include!("../fuzz/register_clouds.rs");

/// The seeds must also reach the registration (not all be rejected before it): most of them give
/// an answer.
#[test]
fn register_clouds_seeds_and_regressions_register_or_fail_cleanly() {
    let mut reg = arps::Registrar::new(&arps::Weights::random(&arps::ModelConfig::tiny(), 0).unwrap()).unwrap();
    let seeds = inputs("seeds/register_clouds");
    assert!(seeds.len() >= 9, "the seeds are committed ({} found)", seeds.len());
    let mut answered = 0;
    for (name, data) in &seeds {
        eprintln!("{name}");
        answered += usize::from(register_clouds_target(&mut reg, data));
    }
    assert!(answered * 2 > seeds.len(), "{answered} of {} seeds answered", seeds.len());
    for (name, data) in inputs("regressions/register_clouds") {
        eprintln!("{name}");
        register_clouds_target(&mut reg, &data);
    }
}
