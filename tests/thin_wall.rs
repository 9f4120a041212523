//! Thin walls: a one-view scan of an L bracket of 2 mm sheet, placed on the inner faces of its
//! walls (a wall's thickness off), is moved onto the outer faces it was scanned on; a flat sheet
//! scanned on one face is said to fit either face.

mod common;

use arps::refine::Start;
use arps::transform::{rotation_error_deg, translation_error};
use arps::{Options, PointCloud, Registrar};
use common::motion;
use nalgebra::Matrix4;

const T: f32 = 2.0; // wall thickness, mm

/// Points on the rectangle from `o` spanned by `u` and `v` (lengths `a`, `b`), `step` apart.
fn rect(o: [f32; 3], u: [f32; 3], v: [f32; 3], (a, b): (f32, f32), step: f32, out: &mut Vec<[f32; 3]>) {
    let (na, nb) = ((a / step).round() as usize, (b / step).round() as usize);
    for i in 0..=na {
        for j in 0..=nb {
            let (s, t) = (a * i as f32 / na as f32, b * j as f32 / nb as f32);
            out.push([0, 1, 2].map(|k| o[k] + s * u[k] + t * v[k]));
        }
    }
}

/// An L bracket: a plate 40 x 30 in x, y (z from 0 to `T`) and one 40 x 30 in z, y (x from 0 to
/// `T`), every face sampled: its outer faces z = 0 and x = 0, its inner faces, ends and sides.
fn bracket(step: f32) -> Vec<[f32; 3]> {
    let (x, y, z) = ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]);
    let mut p = Vec::new();
    rect([0.0, 0.0, 0.0], x, y, (40.0, 30.0), step, &mut p); // outer, under
    rect([0.0, 0.0, 0.0], z, y, (40.0, 30.0), step, &mut p); // outer, behind
    rect([T, 0.0, T], x, y, (40.0 - T, 30.0), step, &mut p); // inner, on the plate
    rect([T, 0.0, T], z, y, (40.0 - T, 30.0), step, &mut p); // inner, on the wall
    rect([40.0, 0.0, 0.0], z, y, (T, 30.0), step, &mut p); // the plate's end
    rect([0.0, 0.0, 40.0], x, y, (T, 30.0), step, &mut p); // the wall's end
    for side in [0.0, 30.0] {
        rect([0.0, side, 0.0], x, z, (40.0, T), step, &mut p);
        rect([0.0, side, 0.0], z, x, (40.0, T), step, &mut p);
    }
    p
}

/// The outer faces only, as one view from outside the L sees them, moved by `m`.
fn outer_view(step: f32, m: &Matrix4<f64>) -> PointCloud {
    let (x, y, z) = ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]);
    let mut p = Vec::new();
    rect([0.0, 0.0, 0.0], x, y, (40.0, 30.0), step, &mut p);
    rect([0.0, 0.0, 0.3], z, y, (39.7, 30.0), step, &mut p);
    PointCloud::new(p).transformed(m)
}

fn from(guess: &Matrix4<f64>) -> Options {
    Options {
        initial_transform: Some(arps::transform::to_rows(guess)),
        starts: vec![Start::Initial],
        network: false,
        max_correspondence_distance: Some(0.6),
        ..Options::default()
    }
}

#[test]
fn a_one_view_scan_placed_on_the_inner_faces_moves_onto_the_outer_ones() {
    let target = PointCloud::new(bracket(0.25));
    let scanner = motion([20.0, -35.0, 10.0], [100.0, -50.0, 30.0]);
    let source = outer_view(0.35, &scanner);
    let truth = arps::transform::rigid_inverse(&scanner);
    // the truth moved a wall's thickness into the L: the scan on the inner faces
    let inner = Matrix4::new_translation(&nalgebra::Vector3::new(T as f64, 0.0, T as f64)) * truth;
    let mut reg = Registrar::with_default_model().unwrap();
    let r = reg.register(&source, &target, &from(&inner)).unwrap();
    let (re, te) = (rotation_error_deg(&r.T_target_source, &truth), translation_error(&r.T_target_source, &truth));
    assert!(re < 0.5 && te < 0.3, "{re:.3} deg, {te:.3} mm off the outer faces (start {:?})", r.start);
}

#[test]
fn a_flat_sheet_scanned_on_one_face_is_said_to_fit_either() {
    // a plate 60 x 40 of 1 mm, both faces and its edges; the scan sees its top face
    let (x, y, z) = ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]);
    let mut p = Vec::new();
    rect([0.0, 0.0, 0.0], x, y, (60.0, 40.0), 0.25, &mut p);
    rect([0.0, 0.0, 1.0], x, y, (60.0, 40.0), 0.25, &mut p);
    for (o, u) in [([0.0, 0.0, 0.0], x), ([0.0, 40.0, 0.0], x)] {
        rect(o, u, z, (60.0, 1.0), 0.25, &mut p);
    }
    for (o, u) in [([0.0, 0.0, 0.0], y), ([60.0, 0.0, 0.0], y)] {
        rect(o, u, z, (40.0, 1.0), 0.25, &mut p);
    }
    let target = PointCloud::new(p);
    let mut top = Vec::new();
    rect([5.0, 5.0, 1.0], x, y, (50.0, 30.0), 0.35, &mut top);
    let scanner = motion([10.0, 25.0, -15.0], [20.0, 10.0, -5.0]);
    let source = PointCloud::new(top).transformed(&scanner);
    let truth = arps::transform::rigid_inverse(&scanner);
    let mut reg = Registrar::with_default_model().unwrap();
    let r = reg.register(&source, &target, &from(&truth)).unwrap();
    assert!(
        r.warnings.iter().any(|w| w.contains("onto a parallel face")),
        "either face fits a flat sheet's one-face scan: {:?}",
        r.warnings
    );
}
