//! Any bytes given to the weights loader must give weights or an error, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = arps::Weights::from_bytes(data);
});
