//! The curriculum (docs/design.md §12): training pairs start with small rotations and translations,
//! high overlap and little noise, and ramp linearly to the paper's protocol (±45°, 0.5, ≥ 70%
//! overlap with 70% crops, σ = 0.01) over `ramp_pairs` training pairs. Validation always uses the
//! full protocol.

use crate::data::PairParams;
use serde::{Deserialize, Serialize};

/// Start values and ramp length. `ramp_pairs = 0` turns the curriculum off.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Curriculum {
    /// Pairs over which the protocol ramps from the start values to the full protocol.
    pub ramp_pairs: u64,
    /// Start: maximum Euler angle per axis, degrees.
    pub angle_deg: f64,
    /// Start: maximum translation.
    pub translation: f64,
    /// Start: crop keep ratio.
    pub keep_ratio: f64,
    /// Start: minimum crop overlap.
    pub min_overlap: f64,
    /// Start: noise sigma.
    pub noise_sigma: f64,
}

impl Default for Curriculum {
    fn default() -> Self {
        Self {
            ramp_pairs: 16_000,
            angle_deg: 10.0,
            translation: 0.1,
            keep_ratio: 0.85,
            min_overlap: 0.9,
            noise_sigma: 0.005,
        }
    }
}

impl Curriculum {
    /// No curriculum: the full protocol from the start.
    pub fn off() -> Self {
        Self { ramp_pairs: 0, ..Self::default() }
    }

    /// Parses `off` or a comma list `pairs=N,angle=A,trans=T,keep=K,overlap=O,noise=S` (unlisted
    /// keys keep their defaults).
    pub fn parse(s: &str) -> Result<Self, String> {
        let s = s.trim();
        if s == "off" || s == "none" || s == "0" {
            return Ok(Self::off());
        }
        let mut c = Self::default();
        for item in s.split(',').filter(|x| !x.trim().is_empty()) {
            let (k, v) = item.split_once('=').ok_or_else(|| format!("curriculum item '{item}' is not key=value"))?;
            let f: f64 = v.trim().parse().map_err(|_| format!("curriculum value '{v}' is not a number"))?;
            match k.trim() {
                "pairs" | "ramp" => c.ramp_pairs = f as u64,
                "angle" => c.angle_deg = f,
                "trans" | "translation" => c.translation = f,
                "keep" => c.keep_ratio = f,
                "overlap" => c.min_overlap = f,
                "noise" => c.noise_sigma = f,
                other => {
                    return Err(format!("unknown curriculum key '{other}' (pairs, angle, trans, keep, overlap, noise)"))
                }
            }
        }
        Ok(c)
    }

    /// Progress in [0, 1] after `pairs_seen` pairs.
    pub fn progress(&self, pairs_seen: u64) -> f64 {
        if self.ramp_pairs == 0 {
            1.0
        } else {
            (pairs_seen as f64 / self.ramp_pairs as f64).min(1.0)
        }
    }

    /// The protocol for the pair at stream position `pairs_seen` (`full` is the target protocol).
    pub fn params(&self, pairs_seen: u64, full: &PairParams) -> PairParams {
        let u = self.progress(pairs_seen);
        let lerp = |a: f64, b: f64| a + (b - a) * u;
        PairParams {
            max_angle_deg: lerp(self.angle_deg, full.max_angle_deg),
            max_translation: lerp(self.translation, full.max_translation),
            keep_ratio: lerp(self.keep_ratio, full.keep_ratio),
            min_overlap: lerp(self.min_overlap, full.min_overlap),
            noise_sigma: lerp(self.noise_sigma, full.noise_sigma),
            ..full.clone()
        }
    }
}
