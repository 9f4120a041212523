//! Index arithmetic at wasm32's 32-bit `usize`, run in Node by `wasm-pack test --node`: an even
//! sample of a large cloud spans all of it (8192 samples of a 600k-point cloud computed
//! `i * len` in `usize`, which wrapped, and the sample covered the cloud's first part only: a
//! 3M-point survey pair registered 0.6 m off in the package and 2 mm off natively).
#![cfg(target_arch = "wasm32")]

use arps::refine::{even_sample, REFINE_POINTS};
use wasm_bindgen_test::wasm_bindgen_test;

#[wasm_bindgen_test]
fn an_even_sample_of_a_large_cloud_spans_it() {
    for len in [600_000usize, 3_000_000] {
        // point i at x = i: the sample's x are the indices it took
        let points: Vec<[f32; 3]> = (0..len).map(|i| [i as f32, 0.0, 0.0]).collect();
        let sample = even_sample(&points, REFINE_POINTS);
        assert_eq!(sample.len(), REFINE_POINTS);
        for (k, p) in sample.iter().enumerate() {
            let want = (k as u64 * len as u64 / REFINE_POINTS as u64) as f32;
            assert_eq!(p[0], want, "sample {k} of {len} points");
        }
        let last = sample[REFINE_POINTS - 1][0] as usize;
        assert!(last >= len - len / REFINE_POINTS - 1, "the sample ends at {last} of {len}");
    }
}
