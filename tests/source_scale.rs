//! `Options::source_scale`: a source in another unit than the target registers in the target's
//! unit, and the answer maps the source as given (its 3x3 part the rotation times the factor);
//! map-grid origins are scaled with the points; a factor of 1 changes nothing; bad factors and
//! guesses that do not carry the factor are refused with errors naming them.

use arps::transform::{from_rows, rotation_error_deg};
use arps::{Error, Options, PointCloud, Registrar};
use nalgebra::{Matrix4, Point3, Vector3};

/// Metres per US survey foot: a LAS survey in feet onto a model in metres.
const FOOT: f64 = 1200.0 / 3937.0;
/// A UTM-like offset (metres).
const FAR: [f64; 3] = [512_345.25, 4_123_456.5, 87.125];

fn fixture(name: &str) -> PointCloud {
    let path = format!("{}/fixtures/wasm/{name}", env!("CARGO_MANIFEST_DIR"));
    arps::io::read_point_cloud(&std::fs::read(&path).unwrap(), name).unwrap()
}

fn truth() -> Matrix4<f64> {
    let path = format!("{}/fixtures/wasm/pair.json", env!("CARGO_MANIFEST_DIR"));
    let pair: serde_json::Value = serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap();
    from_rows(&serde_json::from_value(pair["T_target_source"].clone()).unwrap())
}

/// `cloud` (metres) moved by `offset` and written in `unit` (metres per unit), as f64 points: a
/// cloud with an origin near them.
fn in_unit(cloud: &PointCloud, offset: [f64; 3], unit: f64) -> PointCloud {
    let points: Vec<[f64; 3]> =
        (0..cloud.len()).map(|i| std::array::from_fn(|a| (cloud.point_f64(i)[a] + offset[a]) / unit)).collect();
    PointCloud::from(&points[..])
}

/// The largest distance between where `a` and `b` put `cloud`'s points.
fn gap(a: &Matrix4<f64>, b: &Matrix4<f64>, cloud: &PointCloud) -> f64 {
    (0..cloud.len())
        .map(|i| {
            let p = Point3::from(cloud.point_f64(i));
            (a.transform_point(&p) - b.transform_point(&p)).norm()
        })
        .fold(0.0, f64::max)
}

fn rows(m: &Matrix4<f64>) -> [[f64; 4]; 4] {
    std::array::from_fn(|r| std::array::from_fn(|c| m[(r, c)]))
}

/// `m` with its 3x3 part divided by `f`.
fn unscaled(m: &Matrix4<f64>, f: f64) -> Matrix4<f64> {
    let mut m = *m;
    m.fixed_view_mut::<3, 3>(0, 0).unscale_mut(f);
    m
}

#[test]
fn a_survey_in_feet_on_the_map_grid_registers_onto_metres() {
    let (source, target) = (fixture("source.ply"), fixture("target.ply"));
    let source_ft = in_unit(&source, FAR, FOOT);
    assert!(source_ft.origin[0] > 1e6, "the cloud carries its map-grid origin: {:?}", source_ft.origin);
    let target_far = in_unit(&target, FAR, 1.0);
    let mut registrar = Registrar::with_default_model().unwrap();
    let options = Options { source_scale: Some(FOOT), ..Options::default() };
    let r = registrar.register(&source_ft, &target_far, &options).unwrap();
    // the truth, from the file's feet: into metres, off the grid, the pair's motion, back on it
    let shift = Matrix4::new_translation(&Vector3::from(FAR));
    let feet = Matrix4::new_nonuniform_scaling(&Vector3::repeat(FOOT));
    let expected = shift * truth() * shift.try_inverse().unwrap() * feet;
    let g = gap(&r.T_target_source, &expected, &source_ft);
    assert!(g < 0.02, "the answer puts the feet points {g} m from where the truth does");
    let rigid = unscaled(&r.T_target_source, FOOT);
    arps::transform::check_near_rigid(&rigid).unwrap();
    assert!(rotation_error_deg(&rigid, &truth()) < 1.0);
    assert!(r.confidence > 0.8, "confidence {}", r.confidence);
    assert!(!r.warnings.iter().any(|w| w.contains("differ in size")), "{:?}", r.warnings);
    // the registration of the same survey given in metres, times the unit change
    let metres = registrar.register(&in_unit(&source, FAR, 1.0), &target_far, &Options::default()).unwrap();
    let same = gap(&r.T_target_source, &(metres.T_target_source * feet), &source_ft);
    assert!(same < 1e-4, "{same} from the answer in metres");
    let d = metres.max_correspondence_distance;
    assert!(
        (r.max_correspondence_distance - d).abs() < 1e-6 * d,
        "{} vs {d}: in metres",
        r.max_correspondence_distance
    );

    // the answer is a guess as it is (ICP only from it stays put); a rigid guess is refused
    let again = Options { network: false, initial_transform: Some(rows(&r.T_target_source)), ..options.clone() };
    let from_guess = registrar.register(&source_ft, &target_far, &again).unwrap();
    assert!(gap(&from_guess.T_target_source, &expected, &source_ft) < 0.02);
    let rigid_guess = Options { initial_transform: Some(rows(&rigid)), ..options.clone() };
    let e = registrar.register(&source_ft, &target_far, &rigid_guess).unwrap_err();
    assert!(
        matches!(&e, Error::InvalidOption(m) if m.contains("initialTransform is not rigid once its 3x3 part is divided by sourceScale")),
        "{e}"
    );
}

#[test]
fn a_factor_of_one_changes_nothing_and_bad_factors_are_refused() {
    let (source, target) = (fixture("source.ply"), fixture("target.ply"));
    let mut registrar = Registrar::with_default_model().unwrap();
    let plain = registrar.register(&source, &target, &Options::default()).unwrap();
    let one = registrar.register(&source, &target, &Options { source_scale: Some(1.0), ..Options::default() }).unwrap();
    assert_eq!((plain.T_target_source, plain.confidence), (one.T_target_source, one.confidence));
    for bad in [0.0, -2.0, f64::NAN, f64::INFINITY] {
        let e = registrar.register(&source, &target, &Options { source_scale: Some(bad), ..Options::default() });
        let e = e.unwrap_err();
        assert!(
            matches!(&e, Error::InvalidOption(m) if m.starts_with("sourceScale =") && m.contains("must be a finite number > 0")),
            "{bad}: {e}"
        );
    }
    // a factor that takes the points beyond what f32 holds is named in the error
    let e = registrar.register(&source, &target, &Options { source_scale: Some(1e30), ..Options::default() });
    let e = e.unwrap_err();
    assert!(matches!(&e, Error::InvalidCloud(m) if m.contains("multiplied by sourceScale")), "{e}");
    // and the registrar still works
    let after = registrar.register(&source, &target, &Options::default()).unwrap();
    assert_eq!(after.T_target_source, plain.T_target_source);
}

#[test]
fn a_factor_given_the_wrong_way_round_is_named_with_its_inverse() {
    let (source, target) = (fixture("source.ply"), fixture("target.ply"));
    let source_mm = in_unit(&source, [0.0; 3], 0.001);
    let mut registrar = Registrar::with_default_model().unwrap();
    let wrong = Options { source_scale: Some(1000.0), ..Options::default() };
    let r = registrar.register(&source_mm, &target, &wrong).unwrap();
    let at = r.warnings.iter().position(|w| w.contains("differ in size")).expect("a size warning");
    assert!(
        r.warnings[at].contains("sourceScale = 1000 may be the wrong way round: its inverse, 0.001,"),
        "{:?}",
        r.warnings
    );
    // without a factor the warning says nothing of one
    let r = registrar.register(&source_mm, &target, &Options::default()).unwrap();
    let at = r.warnings.iter().position(|w| w.contains("differ in size")).expect("a size warning");
    assert!(!r.warnings[at].contains("wrong way round"), "{:?}", r.warnings);
    // the right factor: no size warning at all
    let right = Options { source_scale: Some(0.001), ..Options::default() };
    let r = registrar.register(&source_mm, &target, &right).unwrap();
    assert!(!r.warnings.iter().any(|w| w.contains("differ in size")), "{:?}", r.warnings);
}
