//! Any pair of clouds must give a registration or an error (never a panic, never a non-finite or
//! non-rigid answer, never a confidence outside [0, 1]), the same answer bit for bit when asked
//! twice, and the registrar stays usable after an error.
//!
//! The clouds are built from the bytes so that degenerate geometry is common: points on a small
//! integer grid (duplicates, lines, planes), each grown into a cluster of copies, scaled by powers
//! of ten (1e-12 to 1e12) and moved far from zero (georeferenced coordinates), the source often a
//! turned copy of part of the target so that the search reaches its later stages. Layout:
//!
//! * byte 0: flags (`up`, keep the support plane, keep outliers, point-to-point ICP, exhaustive
//!   search, source from the target, large offset, check determinism);
//! * byte 1: copies per point (1 to 16) and the copies' spread;
//! * bytes 2, 3: the source's and the target's scale exponents;
//! * byte 4: where the target's points end and the source's begin;
//! * byte 5: the source's turn (from the target) and its share of the target;
//! * the rest: points, three signed bytes each.
#![no_main]

use arps::{ModelConfig, Registrar, Weights};
use libfuzzer_sys::fuzz_target;
use std::cell::RefCell;

thread_local! {
    static REGISTRAR: RefCell<Registrar> =
        RefCell::new(Registrar::new(&Weights::random(&ModelConfig::tiny(), 0).unwrap()).unwrap());
}

include!("../register_clouds.rs");

fuzz_target!(|data: &[u8]| {
    REGISTRAR.with(|reg| register_clouds_target(&mut reg.borrow_mut(), data));
});
