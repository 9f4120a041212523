//! Stage 7, for a pair whose clouds both stand on a support plane (two scans of an object on a
//! table): whether the object stayed put on the table between the scans.
//!
//! If it did, the two tables are the same table and help: they fix the tilt and the height that
//! a partial object leaves loose. If the object was tipped or turned over, the tables disagree
//! with the object's motion and pull the answer away from it (`BENCHMARK.md`, "A support plane
//! under the scan"). Nothing in the clouds says which before registering, so the pair is
//! registered both ways: with the planes (the pipeline's answer) and without them, and the answer
//! with the planes is refined once more on the clouds without them. When that refinement stays
//! where it started (within [`SAME_DEG`] and twice the final correspondence distance), the
//! object agrees with the tables and the answer with the planes is kept. Otherwise the object was
//! moved on the table, and of the answer without the planes and that refinement, the one the
//! object fits better is kept.

use crate::register::{Options, Registrar, Registration, Search};
use crate::support::Support;
use crate::{transform, Result, Start};

/// Most turn, in degrees, between the answer with the planes and its refinement on the clouds
/// without them for the two to be the same answer.
pub const SAME_DEG: f64 = 2.0;

/// Registers the pair without the planes and chooses between that answer and `with_planes` (the
/// pipeline's answer with them; see the module docs). The registrar's progress is not reported
/// for these passes.
pub(crate) fn choose(
    registrar: &mut Registrar,
    source: &crate::PointCloud,
    target: &crate::PointCloud,
    options: &Options,
    with_planes: Registration,
) -> Result<Registration> {
    let without = Options { support_plane: Support::DropAll, ..options.clone() };
    let (free, _) = registrar.register_once(source, target, &without, &mut |_| {})?;
    // the answer with the planes, refined on the clouds without them
    let from_planes = Options {
        support_plane: Support::DropAll,
        network: false,
        initial_transform: Some(transform::to_rows(&with_planes.T_target_source)),
        starts: vec![Start::Initial],
        search: Search::Exhaustive,
        ..options.clone()
    };
    let (checked, _) = registrar.register_once(source, target, &from_planes, &mut |_| {})?;
    let extra_ms = free.timings.total_ms + checked.timings.total_ms;
    let moved = transform::rotation_error_deg(&checked.T_target_source, &with_planes.T_target_source);
    let shift = transform::translation_error(&checked.T_target_source, &with_planes.T_target_source);
    let mut chosen = if moved <= SAME_DEG && shift <= 2.0 * checked.max_correspondence_distance {
        with_planes
    } else {
        let mut best = if checked.fitness > free.fitness { checked } else { free };
        best.warnings.push(format!(
            "both clouds stand on a plane (a table), but the object does not agree with the planes' motion (it moves {moved:.0} degrees from it): the object was moved on the table between the scans, so the planes were left out (supportPlane set to dropAll does so from the start)"
        ));
        best
    };
    chosen.timings.total_ms += extra_ms;
    Ok(chosen)
}
