//! The shape-bank loader: recursive, all four formats' extensions, degenerate meshes skipped with
//! a reason, split by shape name.
#![cfg(feature = "cli")]

mod common;
use arps::data::bank::{check_mesh, load_dir, split_of};
use arps::data::Split;
use arps::io::Mesh;

fn temp_dir(tag: &str) -> common::scratch::Scratch {
    let d = common::scratch(&format!("bank-{tag}"));
    std::fs::create_dir_all(d.join("sub/deeper")).unwrap();
    d
}

const TETRA_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
const TETRA_OFF: &str = "OFF\n4 4 0\n0 0 0\n2 0 0\n0 2 0\n0 0 2\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
/// A 4 x 4 grid of quads in the plane z = 0: many triangles, but flat.
fn flat_obj() -> String {
    let mut s = String::new();
    for j in 0..5 {
        for i in 0..5 {
            s += &format!("v {i} {j} 0\n");
        }
    }
    for j in 0..4 {
        for i in 0..4 {
            let a = j * 5 + i + 1;
            s += &format!("f {} {} {} {}\n", a, a + 1, a + 6, a + 5);
        }
    }
    s
}

#[test]
fn degenerate_meshes_are_rejected_with_a_reason() {
    let tri = Mesh { vertices: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], triangles: vec![[0, 1, 2]] };
    assert!(check_mesh(&tri).unwrap_err().contains("too few triangles"));
    let zero = Mesh { vertices: vec![[0.0; 3]; 3], triangles: vec![[0, 1, 2]; 6] };
    assert!(check_mesh(&zero).unwrap_err().contains("no surface area"));
    let bad = Mesh { vertices: vec![[0.0; 3]; 3], triangles: vec![[0, 1, 7]; 6] };
    assert!(check_mesh(&bad).unwrap_err().contains("refers beyond"));
}

#[test]
fn loads_recursively_and_skips_with_reasons() {
    let d = temp_dir("load");
    std::fs::write(d.join("a.obj"), TETRA_OBJ).unwrap();
    std::fs::write(d.join("sub/b.OFF"), TETRA_OFF).unwrap();
    std::fs::write(d.join("sub/deeper/flat.obj"), flat_obj()).unwrap();
    std::fs::write(d.join("sub/broken.ply"), "ply\nthis is not a ply file\n").unwrap();
    std::fs::write(d.join("notes.txt"), "not a mesh").unwrap();
    let bank = load_dir(&d).unwrap();
    let names: Vec<&str> = bank.meshes.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["a.obj", "sub/b.OFF"]);
    assert_eq!(bank.meshes[1].mesh.triangles.len(), 4);
    let skipped: Vec<(&str, &str)> = bank.skipped.iter().map(|s| (s.name.as_str(), s.reason.as_str())).collect();
    assert_eq!(skipped.len(), 2, "{skipped:?}");
    assert_eq!(skipped[0].0, "sub/broken.ply");
    assert_eq!(skipped[1].0, "sub/deeper/flat.obj");
    assert!(skipped[1].1.starts_with("flat"), "{skipped:?}");
    assert!(bank.skipped_report().contains("skipped sub/deeper/flat.obj: flat"));
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn split_is_by_name_and_stable() {
    let names: Vec<String> = (0..1000).map(|i| format!("set/mesh{i}.obj")).collect();
    let val = names.iter().filter(|n| split_of(n, 0.2) == Split::Val).count();
    assert!((150..250).contains(&val), "{val}");
    for n in &names {
        assert_eq!(split_of(n, 0.2), split_of(n, 0.2));
        // a larger validation fraction only moves shapes into validation
        if split_of(n, 0.1) == Split::Val {
            assert_eq!(split_of(n, 0.2), Split::Val);
        }
    }
    assert_eq!(split_of("x", 0.0), Split::Train);
    assert_eq!(split_of("x", 1.0), Split::Val);
}
