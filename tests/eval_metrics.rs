//! Metrics, manifests and the recall SVG (no engine needed).
#![cfg(feature = "cli")]

use arps::data::manifest::{self, Entry};
use arps::data::metrics::{
    ambiguous_miss, mcnemar_p, pair_error, recall_svg, recall_vs_rotation, recall_vs_translation, summarize, PairError,
};
use arps::transform::{euler_xyz, from_rotation_translation};
use nalgebra::{Matrix4, Vector3};

fn e(rot_deg: f64, trans: f64) -> PairError {
    PairError { rot_deg, trans }
}

#[test]
fn errors_are_geodesic_degrees_and_scaled_translation() {
    let gt = from_rotation_translation(&euler_xyz(0.2, -0.1, 0.3), &Vector3::new(1.0, 2.0, 3.0));
    let d = from_rotation_translation(&euler_xyz(10f64.to_radians(), 0.0, 0.0), &Vector3::new(0.0, 0.4, 0.0));
    let pred = d * gt;
    let err = pair_error(&pred, &gt, 2.0);
    assert!((err.rot_deg - 10.0).abs() < 1e-9, "{err:?}");
    // t_pred - t_gt = R_d t_gt + t_d - t_gt
    let expect = (d.fixed_view::<3, 3>(0, 0) * Vector3::new(1.0, 2.0, 3.0) + Vector3::new(0.0, 0.4, 0.0)
        - Vector3::new(1.0, 2.0, 3.0))
    .norm()
        / 2.0;
    assert!((err.trans - expect).abs() < 1e-12);
    let nan = Matrix4::from_element(f64::NAN);
    assert_eq!(pair_error(&nan, &gt, 1.0).rot_deg, 180.0);
}

#[test]
fn table_figures_follow_the_paper() {
    let errs = [e(1.0, 0.01), e(14.9, 0.19), e(15.0, 0.05), e(3.0, 0.2), e(40.0, 1.0)];
    let s = summarize(&errs, &[1.0, 2.0, 3.0, 4.0, 5.0], 15.0, 0.2);
    assert_eq!(s.pairs, 5);
    assert!((s.recall - 0.4).abs() < 1e-12, "strict thresholds: {s:?}");
    assert!((s.mre - (1.0 + 14.9 + 15.0 + 3.0 + 40.0) / 5.0).abs() < 1e-12);
    assert!((s.mte - (0.01 + 0.19 + 0.05 + 0.2 + 1.0) / 5.0).abs() < 1e-12);
    assert!((s.rre - (1.0 + 14.9) / 2.0).abs() < 1e-12);
    assert!((s.rte - 0.1).abs() < 1e-12);
    assert!((s.ms_per_pair - 3.0).abs() < 1e-12);
    let none = summarize(&[e(90.0, 1.0)], &[1.0], 15.0, 0.2);
    assert_eq!(none.recall, 0.0);
    assert!(none.rre.is_nan() && none.rte.is_nan());
    // curves are monotone and end at the full recall for large thresholds
    let th: Vec<f64> = (0..=30).map(|i| i as f64).collect();
    let rr = recall_vs_rotation(&errs, &th, 10.0);
    assert!(rr.windows(2).all(|w| w[0] <= w[1]));
    assert_eq!(rr[0], 0.0);
    let rt = recall_vs_translation(&errs, &[0.0, 0.1, 0.5, 2.0], 100.0);
    assert_eq!(rt, vec![0.0, 0.4, 0.8, 1.0]);
}

#[test]
fn svg_has_a_curve_per_method_in_each_panel() {
    let methods = vec![
        ("network".to_string(), vec![e(5.0, 0.1), e(20.0, 0.3)]),
        ("ICP <identity> & co".to_string(), vec![e(1.0, 0.01)]),
    ];
    let svg = recall_svg(&methods, 15.0, 0.2, 30.0, 0.4, "test");
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    assert_eq!(svg.matches("<polyline").count(), 4);
    assert!(svg.contains("ICP &lt;identity&gt; &amp; co"));
}

#[test]
fn manifest_round_trip() {
    let t = from_rotation_translation(&euler_xyz(0.3, 0.2, -0.1), &Vector3::new(0.1, -0.2, 0.3));
    let entries = vec![Entry {
        name: "00000-chair".into(),
        source: "00000_source.ply".into(),
        target: "00000_target.ply".into(),
        overlap_threshold: 0.05,
        note: "a note".into(),
        T_target_source: t,
    }];
    let text = manifest::format(&entries);
    assert!(text.starts_with(manifest::HEADER));
    let back = manifest::parse(&text).unwrap();
    assert_eq!(back, entries, "shortest round-trip numbers are exact");
    assert!(manifest::parse("name\tsource\n a\tb\n").is_err());
    let e = back[0].source_path(std::path::Path::new("/x/y/pairs.tsv"));
    assert_eq!(e, std::path::PathBuf::from("/x/y/00000_source.ply"));
}

#[test]
fn reads_the_real_scan_manifest() {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/scans/pairs.tsv");
    if !p.exists() {
        eprintln!("skipped: {} not present", p.display());
        return;
    }
    let entries = manifest::read(&p).unwrap();
    assert!(entries.len() >= 6);
    assert!(entries.iter().any(|e| e.name == "stanford-bunny"));
}

#[test]
fn mcnemar_p_is_the_exact_two_sided_binomial_tail() {
    // reference values from the binomial sums (Python's math.comb)
    assert_eq!(mcnemar_p(0, 0), 1.0);
    assert_eq!(mcnemar_p(1, 1), 1.0);
    assert!((mcnemar_p(0, 5) - 0.0625).abs() < 1e-12);
    assert!((mcnemar_p(8, 4) - 0.3876953125).abs() < 1e-12);
    assert!((mcnemar_p(13, 48) - 7.665168380445453e-6).abs() < 1e-15);
    // symmetric, and fine for large counts (no overflow in the binomials)
    assert_eq!(mcnemar_p(48, 13), mcnemar_p(13, 48));
    assert!((mcnemar_p(300, 250) - 0.036578745549102704).abs() < 1e-12);
    let tiny = mcnemar_p(0, 2000);
    assert!(tiny.is_finite() && (0.0..1e-300).contains(&tiny), "{tiny}");
    assert!(mcnemar_p(1000, 1000) == 1.0);
}

#[test]
fn an_ambiguous_miss_is_a_miss_that_fits_within_the_margin_of_the_truth() {
    assert!(ambiguous_miss(false, Some(0.895), 0.9, 0.01));
    assert!(ambiguous_miss(false, Some(0.95), 0.9, 0.01), "fitting better than the truth counts");
    assert!(!ambiguous_miss(false, Some(0.88), 0.9, 0.01), "fits worse than the truth");
    assert!(!ambiguous_miss(true, Some(0.9), 0.9, 0.01), "recalled pairs are not misses");
    assert!(!ambiguous_miss(false, None, 0.9, 0.01), "a failed call has no fitness");
}
