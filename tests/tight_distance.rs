//! A `maxCorrespondenceDistance` tighter than the default sets how precisely the answer fits,
//! not how far the search reaches: the ICP stages start from the default distance's and halve
//! down to it.

mod common;

use arps::refine::Start;
use arps::{Options, Registrar};
use common::{bumpy_surface, crop, errors, motion};

#[test]
fn a_tight_distance_still_brings_a_start_from_as_far_as_the_default() {
    // a dense part of a bumpy surface, sampled apart from the whole, turned 15 degrees off the
    // only start (the centroids': the network off)
    let target = bumpy_surface(40_000, 0.0);
    let part = crop(&bumpy_surface(40_000, 0.37), [0.3, 0.8, -0.5], 0.6);
    let gt = motion([8.0, -9.0, 7.0], [0.05, -0.08, 0.04]);
    let source = part.transformed(&arps::transform::rigid_inverse(&gt));
    let mut registrar = Registrar::with_default_model().unwrap();
    let base = Options { network: false, starts: vec![Start::Centroids], ..Options::default() };
    let at_default = registrar.register(&source, &target, &base).unwrap();
    let (rot, trans) = errors(&at_default.T_target_source, &gt);
    assert!(rot < 0.5 && trans < 0.01, "at the default distance: {rot} degrees, {trans}");
    // an eighth of it: about the samples' spacing; the stages at 4, 2 and 1 times it alone
    // leave the start where it was
    let tight = Options { max_correspondence_distance: Some(at_default.max_correspondence_distance / 8.0), ..base };
    let r = registrar.register(&source, &target, &tight).unwrap();
    let (rot, trans) = errors(&r.T_target_source, &gt);
    assert!(rot < 0.2 && trans < 0.005, "at an eighth of it: {rot} degrees, {trans}");
}
