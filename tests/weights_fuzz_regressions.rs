//! `Weights::from_bytes` on damaged files: every truncation and a sweep of byte corruptions of
//! a valid tiny weights file give an error (corruptions inside tensor data too: the checksum),
//! never a panic. The fuzz target `weights_from_bytes` (fuzz/) found no panic in its runs; this
//! keeps a cheap deterministic version of it in the test suite.

use arps::{ModelConfig, StoreAs, Weights};

fn valid() -> Vec<u8> {
    Weights::random(&ModelConfig::tiny(), 3).unwrap().to_bytes(StoreAs::F16).unwrap()
}

#[test]
fn truncations_are_errors() {
    let b = valid();
    assert!(Weights::from_bytes(&b).is_ok());
    for len in (0..b.len()).step_by(7).chain([1, 7, 8, 9, b.len() - 1]) {
        assert!(Weights::from_bytes(&b[..len]).is_err(), "truncated to {len} bytes read fine");
    }
}

#[test]
fn corrupted_bytes_do_not_panic() {
    let b = valid();
    let header_len = u64::from_le_bytes(b[..8].try_into().unwrap()) as usize + 8;
    for i in (0..header_len).chain((header_len..b.len()).step_by(97)) {
        for v in [0u8, b'"', b'9', 0xff] {
            let mut c = b.clone();
            c[i] = v;
            let read = Weights::from_bytes(&c);
            assert!(i < header_len || c[i] == b[i] || read.is_err(), "byte {i} set to {v} read fine");
        }
    }
    // A header length far past the end.
    let mut c = b.clone();
    c[..8].copy_from_slice(&u64::MAX.to_le_bytes());
    assert!(Weights::from_bytes(&c).is_err());
    // f16 NaN in tensor data is rejected.
    let mut c = b.clone();
    c[header_len..header_len + 2].copy_from_slice(&0x7e00u16.to_le_bytes());
    let e = Weights::from_bytes(&c).unwrap_err().to_string();
    assert!(e.contains("non-finite"), "{e}");
}
