//! Cancelling a registration (`arps::Cancel`, `Registrar::register_cancellable`): a call
//! cancelled from another thread stops early with `Error::Cancelled`, one given a cancelled
//! handle does not start, and the registrar stays usable; a call not cancelled gives the same
//! answer as `register`.

mod common;

use arps::{Cancel, Error, Options, PointCloud, Registrar, Search};
use common::{bumpy_surface, fixture_pair, motion};
use std::time::Instant;

#[test]
fn a_handle_not_cancelled_changes_nothing_and_a_cancelled_one_stops_the_call() {
    let (source, target, _) = fixture_pair(0);
    let mut reg = Registrar::with_default_model().unwrap();
    let plain = reg.register(&source, &target, &Options::default()).unwrap();
    let handle = Cancel::new();
    let r = reg.register_cancellable(&source, &target, &Options::default(), &mut |_| {}, &handle).unwrap();
    assert_eq!(r.T_target_source, plain.T_target_source);
    assert_eq!(r.confidence, plain.confidence);
    handle.cancel();
    let e = reg.register_cancellable(&source, &target, &Options::default(), &mut |_| {}, &handle).unwrap_err();
    assert!(matches!(e, Error::Cancelled), "{e}");
    assert!(e.to_string().contains("cancelled"), "{e}");
    // the registrar is still usable, with the same answer
    let again = reg.register(&source, &target, &Options::default()).unwrap();
    assert_eq!(again.T_target_source, plain.T_target_source);
}

/// Options that each lie in their range but together take long (every start refined, no voxels,
/// a tight distance and thousands of ICP iterations): cancelled from another thread after a tenth
/// of the time the call takes in full, it returns `Error::Cancelled` in well under that time,
/// and the registrar then registers as before.
#[test]
fn a_long_registration_stops_soon_after_it_is_cancelled() {
    let target = bumpy_surface(60_000, 0.0);
    let source: PointCloud = bumpy_surface(60_000, 0.3).transformed(&motion([20.0, -10.0, 35.0], [0.2, 0.1, -0.1]));
    let heavy = Options {
        search: Search::Exhaustive,
        voxel_size: Some(0.0),
        icp_max_iterations: 5_000,
        max_correspondence_distance: Some(0.002),
        ..Options::default()
    };
    let mut reg = Registrar::with_default_model().unwrap();
    let started = Instant::now();
    reg.register(&source, &target, &heavy).unwrap();
    let whole = started.elapsed();
    let handle = Cancel::new();
    let canceller = {
        let handle = handle.clone();
        std::thread::spawn(move || {
            std::thread::sleep(whole / 10);
            handle.cancel();
        })
    };
    let started = Instant::now();
    let e = reg.register_cancellable(&source, &target, &heavy, &mut |_| {}, &handle).unwrap_err();
    let took = started.elapsed();
    canceller.join().unwrap();
    assert!(matches!(e, Error::Cancelled), "{e}");
    assert!(took < whole / 2, "stopped after {took:?}; the whole call takes {whole:?}");
    let (s, t, _) = fixture_pair(1);
    let fresh = Registrar::with_default_model().unwrap().register(&s, &t, &Options::default()).unwrap();
    let r = reg.register(&s, &t, &Options::default()).unwrap();
    assert_eq!(r.T_target_source, fresh.T_target_source);
}
