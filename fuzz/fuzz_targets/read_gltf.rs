//! glTF: the bytes as a `.gltf` file when they start with `{`, else as a `.glb`
//! (`gltf_target.rs`).
#![no_main]

use libfuzzer_sys::fuzz_target;

include!("../gltf_target.rs");

fuzz_target!(|data: &[u8]| {
    let _ = gltf_target(data);
});
