//! The integer linear layer's simd128 kernel (`src/nn/qlinear.rs`), run in Node by
//! `wasm-pack test --node`: the same bits as the plain-Rust kernel, on shapes that end on every
//! lane of a step and on a lone last row (the native tests check the x86-64 kernels the same way).
#![cfg(target_arch = "wasm32")]

use arps::nn::QuantWeight;
use wasm_bindgen_test::wasm_bindgen_test;

#[wasm_bindgen_test]
fn simd_integer_layer_matches_the_portable_kernel() {
    for (rows, k, out) in [(1, 1, 1), (3, 7, 5), (2, 8, 4), (5, 17, 3), (9, 130, 9), (128, 128, 128), (33, 256, 64)] {
        let q: Vec<i8> = (0..out * k).map(|i| ((i as u32).wrapping_mul(2_654_435_761) >> 24) as i8).collect();
        let scale: Vec<f32> = (0..out).map(|o| 0.01 + 0.003 * o as f32).collect();
        let w = QuantWeight::new(&q, &scale, out, k).unwrap();
        let x: Vec<f32> = (0..rows * k).map(|i| ((i * 53 % 97) as f32 - 48.0) / 7.0).collect();
        let bias: Vec<f32> = (0..out).map(|o| o as f32 * 0.25 - 1.0).collect();
        let (mut simd, mut plain, mut t) =
            (vec![0.0f32; rows * out], vec![0.0f32; rows * out], vec![0.0f32; rows * out]);
        assert!(w.forward(&x, rows, &mut simd, Some(&bias), false));
        assert!(w.forward(&x, rows, &mut t, Some(&bias), true));
        assert!(w.forward_portable(&x, rows, &mut plain, Some(&bias)));
        for r in 0..rows {
            for o in 0..out {
                let (a, b) = (simd[r * out + o], plain[r * out + o]);
                assert_eq!(a.to_bits(), b.to_bits(), "{rows}x{k}x{out} [{r}, {o}]: {a} vs {b}");
                assert_eq!(t[o * rows + r].to_bits(), b.to_bits());
            }
        }
    }
}
