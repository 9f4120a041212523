//! The k-d tree's leaf scans in WebAssembly's SIMD (`src/spatial/chunk.rs`), run in Node by
//! `wasm-pack test --node`: every query against brute force, on clouds whose leaves end on every
//! lane of a chunk (the native tests check the plain-Rust scans the same way).
#![cfg(target_arch = "wasm32")]

use arps::spatial::KdIndex;
use wasm_bindgen_test::wasm_bindgen_test;

fn cloud(n: usize) -> Vec<[f32; 3]> {
    (0..n)
        .map(|i| {
            let f = i as f32;
            [(f * 0.37).sin() * 3.0, (f * 0.11).cos() * 2.0, ((f * 0.05).sin() * 4.0).round() * 0.25]
        })
        .collect()
}

fn d2(p: &[f32; 3], q: &[f32; 3]) -> f32 {
    let (dx, dy, dz) = (p[0] - q[0], p[1] - q[1], p[2] - q[2]);
    dx * dx + dy * dy + dz * dz
}

#[wasm_bindgen_test]
fn simd_leaf_scans_match_brute_force() {
    for n in [1, 2, 3, 5, 18, 35, 61, 129, 1000, 1003] {
        let mut pts = cloud(n);
        pts.extend([[0.5, 0.5, 0.5]; 6]); // equal distances
        let idx = KdIndex::new(&pts);
        let mut out = Vec::new();
        for (k, p) in pts.iter().enumerate().step_by(3) {
            let q = [p[0] + 0.01, p[1] - 0.02, p[2] + 0.015];
            let mut all: Vec<f32> = pts.iter().map(|p| d2(p, &q)).collect();
            all.sort_by(f32::total_cmp);
            let (nearest, second) = (all[0], all.get(1).copied().unwrap_or(f32::INFINITY));
            for hint in [None, Some(k), Some(k * 7 % pts.len())] {
                let (i, d) = idx.nearest_within(&q, f32::INFINITY, hint).expect("a nearest point");
                assert_eq!((d, d2(&pts[i], &q)), (nearest, nearest), "{n} points, hint {hint:?}");
                assert_eq!(idx.nearest_within(&q, nearest, hint), None);
                let (found, floor) = idx.nearest_within_and_floor(&q, f32::INFINITY, hint);
                assert_eq!(found.map(|f| f.1), Some(nearest));
                assert!(
                    floor >= nearest && floor <= second * (1.0 + 1e-5),
                    "{n} points: floor {floor}, second {second}"
                );
                let (none, floor) = idx.nearest_within_and_floor(&q, nearest * 0.5, hint);
                assert_eq!(none, None);
                assert!(floor >= nearest * 0.5 && floor <= nearest * (1.0 + 1e-5));
            }
            idx.knn_into(&q, 9, &mut out);
            assert_eq!(out.iter().map(|e| e.1).collect::<Vec<_>>(), all[..all.len().min(9)].to_vec());
            idx.within_into(&q, all[all.len() / 3], usize::MAX, &mut out);
            assert_eq!(out.len(), all.iter().filter(|&&d| d <= all[all.len() / 3]).count());
        }
    }
}
