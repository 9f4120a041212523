//! Procedural shapes: every category gives valid, deterministic, distinct meshes.
#![cfg(feature = "cli")]

use arps::data::bank::check_mesh;
use arps::data::pairs::normalize_shape;
use arps::data::{generate, Category, CATEGORIES};

#[test]
fn twenty_modelnet_categories_in_order() {
    let names: Vec<&str> = CATEGORIES.iter().map(|c| c.name()).collect();
    assert_eq!(
        names,
        [
            "airplane",
            "bathtub",
            "bed",
            "bench",
            "bookshelf",
            "bottle",
            "bowl",
            "car",
            "chair",
            "cone",
            "cup",
            "curtain",
            "desk",
            "door",
            "dresser",
            "flower_pot",
            "glass_box",
            "guitar",
            "keyboard",
            "lamp"
        ]
    );
    for c in CATEGORIES {
        assert_eq!(Category::from_name(c.name()), Some(c));
    }
}

#[test]
fn every_category_gives_valid_meshes() {
    for c in CATEGORIES {
        for seed in 0..6 {
            let m = generate(c, seed);
            assert!(m.triangles.len() >= 12, "{c} {seed}: {} triangles", m.triangles.len());
            assert!(m.vertices.iter().all(|p| p.iter().all(|v| v.is_finite())), "{c} {seed}: non-finite vertex");
            assert!(m.surface_area() > 0.0, "{c} {seed}: no area");
            // in range, positive area, not flat
            check_mesh(&m).unwrap_or_else(|e| panic!("{c} {seed}: {e}"));
            let cloud = m.sample_surface(2048, seed).unwrap();
            let (n, _, s) = normalize_shape(&cloud);
            assert!(s > 0.0);
            let (lo, hi) = n.bounds();
            for a in 0..3 {
                assert!(lo[a] >= -1.0 - 1e-5 && hi[a] <= 1.0 + 1e-5, "{c} {seed}: {lo:?} {hi:?}");
            }
            let max_ext = (0..3).map(|a| hi[a] - lo[a]).fold(0.0f32, f32::max);
            assert!((max_ext - 2.0).abs() < 1e-4, "{c} {seed}: largest extent {max_ext}");
        }
    }
}

#[test]
fn deterministic_per_seed_and_distinct_across_seeds() {
    for c in CATEGORIES {
        assert_eq!(generate(c, 7), generate(c, 7), "{c}");
        let meshes: Vec<_> = (0..8).map(|s| generate(c, s)).collect();
        for i in 0..meshes.len() {
            for j in i + 1..meshes.len() {
                assert_ne!(meshes[i].vertices, meshes[j].vertices, "{c}: seeds {i} and {j} coincide");
            }
        }
    }
}
