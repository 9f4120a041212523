//! Training and evaluation data (CLI/trainer builds only): procedural ModelNet-like shapes, a
//! shape-bank loader for real meshes, the paper's pair protocol (docs/design.md §8), pair sets on
//! disk (PLY files + a `pairs.tsv` manifest), and the paper's metrics (docs/design.md §9).
//!
//! * [`shapes`]: [`shapes::generate`]`(category, seed)` for the 20 ModelNet20 categories.
//! * [`bank`]: [`bank::load_dir`] reads OBJ/OFF/PLY/STL meshes recursively, skipping degenerate
//!   ones with a reason; [`bank::split_of`] splits them by shape (hash of the relative path).
//! * [`pairs`]: [`pairs::make_pair`] builds one seeded pair; [`pairs::Pair::engine_frames`] maps it
//!   into the frames the engine's network sees.
//! * [`source`]: [`source::ShapeSource`], procedural + bank shapes with a train/validation split
//!   by shape, never by pair.
//! * [`manifest`]: reading and writing `pairs.tsv` (the `fixtures/pairs/pairs.tsv` format)
//!   and the `pairs.json` sidecar.
//! * [`metrics`]: rotation/translation errors, the paper's table figures, recall curves as SVG.

pub mod bank;
pub mod manifest;
pub mod metrics;
pub mod pairs;
pub mod shapes;
pub mod source;

pub use bank::{Bank, NamedMesh};
pub use pairs::{make_pair, EnginePair, Pair, PairParams};
pub use shapes::{generate, Category, CATEGORIES};
pub use source::{ShapeSource, Split};

/// Mixes a value and a stream tag into a well-spread 64-bit seed (SplitMix64 finaliser). Used to
/// derive independent, platform-stable seeds (per shape, per pair, per stage).
pub fn mix(value: u64, tag: u64) -> u64 {
    let mut z = value.wrapping_add(tag.wrapping_mul(0x9E37_79B9_7F4A_7C15)).wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A hash's top 53 bits as a uniform draw in [0, 1) (platform-stable).
pub fn unit_of_hash(h: u64) -> f64 {
    (h >> 11) as f64 / (1u64 << 53) as f64
}

/// FNV-1a 64-bit hash of a string (stable across platforms and releases; used for splits).
pub fn fnv1a(s: &str) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in s.bytes() {
        h ^= b as u64;
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}
