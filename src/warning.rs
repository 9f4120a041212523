//! What a registration's warnings are about, as codes a caller can test for.
//!
//! A [`Registration`](crate::Registration) carries its warnings twice: as sentences
//! (`warnings`, for people: they name figures and what to do, and may be reworded) and, in the
//! same order, as [`WarningCode`]s (`warningCodes` in JS and JSON), for code that acts on a kind
//! of warning (`result.warningCodes.includes("sizeMismatch")`) without matching the sentences.

use serde::{Deserialize, Serialize};

/// The kind of a registration's warning: `warningCodes[i]` is the kind of `warnings[i]`. One
/// code may come with several sentences (the source's and the target's, or two causes of one
/// doubt). New codes may be added (in Rust the enum is `#[non_exhaustive]`: a `match` needs a
/// wildcard arm); a caller that meets one it does not know should show the sentence.
///
/// * `"lowConfidence"`: the confidence is below 0.5, or another pose fits about as well
///   (`alternatives`): the alignment may be wrong. Comes with every result whose `confidence` is
///   below 0.5.
/// * `"sizeMismatch"`: the clouds differ in size by a large factor: probably different units
///   (metres and millimetres); the option `sourceScale` scales the source.
/// * `"coarseCoordinates"`: a cloud's coordinates were rounded to 32-bit floats far from zero (a
///   map grid given as `Float32Array`, a file that stores floats), to steps that can make the
///   answer as coarse.
/// * `"distanceTooFine"`: the distance the answer is judged at is finer than `f32` coordinates
///   resolve there.
/// * `"distanceTooWide"`: the source is small against the distance the answer is judged at: it fits
///   about as well turned or moved, so the fit cannot confirm its pose (different units, or too
///   wide a `maxCorrespondenceDistance`).
/// * `"nearlyLine"`: a cloud is nearly a line: the rotation about it is weakly held.
/// * `"bothFlat"`: both clouds are flat: sliding within the plane and turning about its normal are
///   held only by their outlines.
/// * `"freeMotion"`: the fit leaves a motion free (a surface of revolution, a straight pipe or
///   tunnel, a plane): only the clouds' edges hold the answer along it (`evidence.constraint`).
/// * `"thinWall"`: the source fits about as well moved onto a parallel face within ten final
///   distances: the other face of a thin wall or sheet, or the next of a repeated structure (a
///   building's floors one storey apart at a default distance of half a metre).
/// * `"mirrorImage"`: a mirror image of the source fits clearly better: one cloud is probably
///   mirrored (a left part for a right one, an axis flipped on export).
/// * `"lowOverlap"`: less of the source lies on the target than `sourceOverlap` says it should.
/// * `"notUpright"`: with `up`: a tilted pose fits clearly better than the upright answer (the
///   clouds were not both captured level).
/// * `"unrefined"`: no start could be refined (or none ended upright with `up`): the answer is the
///   network's estimate or the initial transform, unrefined.
/// * `"turnedFromGuess"`: the answer turned far from `initialTransform` (more than 60 degrees; its
///   confidence is then at most 0.25): the guess was off, or the answer is a look-alike. With
///   `starts: ["initial"]`, the guess as the one start, it also says how far the answer moved from
///   the guess whenever it ended at another pose (no cap below 60 degrees).
/// * `"farFromGuess"`: the answer places the source far from where `initialTransform` does: a
///   look-alike elsewhere (a repeated room, the next bay) if the guess placed it.
/// * `"heldByGuess"`: along a motion the fit leaves free (or barely holds, when the answer turned
///   more than 10 degrees from the guess), the answer follows `initialTransform`: the guess, not
///   the clouds, placed it there (the result names the motion in `freeMotions`).
/// * `"betterPoseNotTaken"`: with `search: "local"`: a pose the probes found fits better than the
///   answer; it is offered among the alternatives, not taken.
/// * `"fewPoints"`: the source has too few points to be sure of any answer, or the clouds are too
///   sparse for the distance the answer is judged at (points many times that distance apart).
/// * `"networkResampled"`: a cloud has fewer points than the network takes: it saw some twice (the
///   answer is still refined on every point).
/// * `"nonFiniteDropped"`: points with a non-finite coordinate (or one beyond 1e18) were left out
///   (`nonFinite: "drop"`).
/// * `"outliersDropped"`: outliers were left out (`outliers: "drop"`).
/// * `"supportPlaneDropped"`: a support plane (a table, a turntable, the floor) was left out
///   (`supportPlane: "drop"`).
/// * `"pointsAtZero"`: several points lie exactly at (0, 0, 0), as a depth camera writes its
///   pixels without a return: they are registered as points; remove them.
/// * `"meshVertices"`: the CLI read a mesh file's vertices as the cloud (`--surface-points` samples
///   its surface).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
#[cfg_attr(feature = "ts", derive(ts_rs::TS))]
#[non_exhaustive]
pub enum WarningCode {
    /// `"lowConfidence"`: the alignment may be wrong (see the type's docs).
    LowConfidence,
    /// `"sizeMismatch"`: the clouds' sizes differ: different units? (see the type's docs).
    SizeMismatch,
    /// `"coarseCoordinates"`: coordinates rounded to f32 far from zero (see the type's docs).
    CoarseCoordinates,
    /// `"distanceTooFine"`: the judging distance is finer than f32 resolves (see the type's docs).
    DistanceTooFine,
    /// `"distanceTooWide"`: the source is small against the judging distance (see the type's docs).
    DistanceTooWide,
    /// `"nearlyLine"`: a cloud is nearly a line (see the type's docs).
    NearlyLine,
    /// `"bothFlat"`: both clouds are flat (see the type's docs).
    BothFlat,
    /// `"freeMotion"`: the fit leaves a motion free (see the type's docs).
    FreeMotion,
    /// `"thinWall"`: the other face of a thin wall, or the next of a repeat, fits alike (see the
    /// type's docs).
    ThinWall,
    /// `"mirrorImage"`: a mirror image fits clearly better (see the type's docs).
    MirrorImage,
    /// `"lowOverlap"`: less overlap than `sourceOverlap` says (see the type's docs).
    LowOverlap,
    /// `"notUpright"`: a tilted pose fits better than the upright answer (see the type's docs).
    NotUpright,
    /// `"unrefined"`: no start could be refined (see the type's docs).
    Unrefined,
    /// `"turnedFromGuess"`: the answer turned far from `initialTransform` (see the type's docs).
    TurnedFromGuess,
    /// `"farFromGuess"`: the answer lies far from where `initialTransform` puts it (see the type's docs).
    FarFromGuess,
    /// `"heldByGuess"`: `initialTransform` placed the answer along a free or barely held motion (see the type's docs).
    HeldByGuess,
    /// `"betterPoseNotTaken"`: with `search: "local"`, a better-fitting pose was not taken (see the type's docs).
    BetterPoseNotTaken,
    /// `"fewPoints"`: too few source points, or too sparse clouds, to be sure (see the type's docs).
    FewPoints,
    /// `"networkResampled"`: fewer points than the network takes (see the type's docs).
    NetworkResampled,
    /// `"nonFiniteDropped"`: non-finite points left out (see the type's docs).
    NonFiniteDropped,
    /// `"outliersDropped"`: outliers left out (see the type's docs).
    OutliersDropped,
    /// `"supportPlaneDropped"`: a support plane left out (see the type's docs).
    SupportPlaneDropped,
    /// `"pointsAtZero"`: points exactly at (0, 0, 0) (see the type's docs).
    PointsAtZero,
    /// `"meshVertices"`: the CLI read a mesh's vertices (see the type's docs).
    MeshVertices,
}

impl WarningCode {
    /// Every code, in the order declared.
    pub const ALL: [WarningCode; 24] = [
        WarningCode::LowConfidence,
        WarningCode::SizeMismatch,
        WarningCode::CoarseCoordinates,
        WarningCode::DistanceTooFine,
        WarningCode::DistanceTooWide,
        WarningCode::NearlyLine,
        WarningCode::BothFlat,
        WarningCode::FreeMotion,
        WarningCode::ThinWall,
        WarningCode::MirrorImage,
        WarningCode::LowOverlap,
        WarningCode::NotUpright,
        WarningCode::Unrefined,
        WarningCode::TurnedFromGuess,
        WarningCode::FarFromGuess,
        WarningCode::HeldByGuess,
        WarningCode::BetterPoseNotTaken,
        WarningCode::FewPoints,
        WarningCode::NetworkResampled,
        WarningCode::NonFiniteDropped,
        WarningCode::OutliersDropped,
        WarningCode::SupportPlaneDropped,
        WarningCode::PointsAtZero,
        WarningCode::MeshVertices,
    ];
}

/// One warning: its kind and its sentence.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Warning {
    /// What it is about.
    pub code: WarningCode,
    /// The sentence, for people.
    pub message: String,
}

impl Warning {
    /// A warning of kind `code` saying `message`.
    pub fn new(code: WarningCode, message: impl Into<String>) -> Self {
        Self { code, message: message.into() }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_are_camel_case_and_distinct() {
        let names: Vec<String> = WarningCode::ALL.iter().map(|c| serde_json::to_string(c).unwrap()).collect();
        assert!(names.iter().all(|n| n.starts_with("\"") && n.chars().nth(1).is_some_and(|c| c.is_ascii_lowercase())));
        let mut unique = names.clone();
        unique.sort();
        unique.dedup();
        assert_eq!(unique.len(), names.len());
        assert_eq!(serde_json::to_string(&WarningCode::SizeMismatch).unwrap(), "\"sizeMismatch\"");
    }
}
