//! Vehicles: airplane, car. x points forward, z up.

use super::parts::*;
use crate::io::Mesh;
use nalgebra::Matrix4;
use std::f64::consts::FRAC_PI_2;

/// Maps a lathe made along z (from 0 to `len`) onto the x axis, nose at +x.
fn z_to_x() -> Matrix4<f64> {
    rotate(1, FRAC_PI_2)
}

/// (a, b, c) -> (a, y0 - c, b): an outline drawn in the xz plane (side view), extruded by `d`
/// along z, lands between y = y0 - d and y = y0 (a proper rotation plus a shift).
#[rustfmt::skip]
fn side_view(y0: f64) -> Matrix4<f64> {
    Matrix4::new(
        1.0, 0.0, 0.0, 0.0,
        0.0, 0.0, -1.0, y0,
        0.0, 1.0, 0.0, 0.0,
        0.0, 0.0, 0.0, 1.0,
    )
}

/// A wing-like plate: root chord `cr` at y = 0 with leading edge at x = 0, tip chord `ct` at
/// y = `span` with leading edge at x = -`sweep`; thickness `t` (centred on z = 0).
fn plate(cr: f64, ct: f64, span: f64, sweep: f64, t: f64) -> Mesh {
    let outline = [[0.0, 0.0], [-sweep, span], [-sweep - ct, span], [-cr, 0.0]];
    let mut m = extrude(&outline, t);
    for p in &mut m.vertices {
        p[2] -= (t * 0.5) as f32;
    }
    m
}

pub fn airplane(r: &mut Dice) -> Mesh {
    let mut s = Shape::default();
    let len = r.u(8.0, 14.0);
    let rad = len * r.u(0.045, 0.07);
    let nose = r.u(0.1, 0.2);
    let tail = r.u(0.25, 0.4);
    let n = 16;
    let prof: Vec<(f64, f64)> = (0..=n)
        .map(|i| {
            let u = i as f64 / n as f64;
            let rr = if u < tail {
                rad * (0.25 + 0.75 * (u / tail).powf(0.7))
            } else if u > 1.0 - nose {
                rad * (1.0 - ((u - 1.0 + nose) / nose).powi(2)).max(0.0).sqrt()
            } else {
                rad
            };
            (rr, len * u)
        })
        .collect();
    let mut prof = prof;
    prof.insert(0, (0.0, 0.0));
    s.add(lathe(&prof, 16, false), &(translate([-len / 2.0, 0.0, 0.0]) * z_to_x()));
    // main wings, low or high mounted, swept, with dihedral
    let span = len * r.u(0.4, 0.6);
    let cr = len * r.u(0.14, 0.22);
    let ct = cr * r.u(0.25, 0.5);
    let sweep = span * r.u(0.05, 0.45);
    let wx = r.u(0.05, 0.2) * len;
    let wz = rad * r.pick(&[-0.6, 0.0, 0.7]);
    let dihedral = r.u(-0.03, 0.12);
    let wing_t = rad * 0.2;
    for side in [-1.0f64, 1.0] {
        let w = plate(cr, ct, span, sweep, wing_t);
        let flip = if side < 0.0 {
            nalgebra::Matrix4::new_nonuniform_scaling(&nalgebra::Vector3::new(1.0, -1.0, 1.0))
        } else {
            Matrix4::identity()
        };
        s.add(w, &(translate([wx, 0.0, wz]) * flip * rotate(0, dihedral)));
    }
    // engines: none (a propeller at the nose), two or four under the wings
    let engines = r.pick(&[0, 2, 2, 4]);
    if engines == 0 {
        s.add_at(slab([0.05 * len, 0.02 * len, len * 0.22]), [len / 2.0 + 0.02 * len, 0.0, -len * 0.11]);
        s.add_at(slab([0.05 * len, len * 0.22, 0.02 * len]), [len / 2.0 + 0.02 * len, 0.0, -0.01 * len]);
    } else {
        let er = rad * r.u(0.35, 0.5);
        let el = cr * r.u(0.6, 0.9);
        for k in 0..engines / 2 {
            let y = span * (0.3 + 0.3 * k as f64);
            let x = wx - sweep * y / span + el * 0.3;
            for side in [-1.0, 1.0] {
                s.add(
                    frustum(er, er * 0.8, el, 12),
                    &(translate([x, side * y, wz - er - wing_t]) * rotate(1, -FRAC_PI_2)),
                );
            }
        }
    }
    // tail: horizontal stabilisers and a fin (T-tail sometimes)
    let tspan = span * r.u(0.25, 0.4);
    let tcr = cr * r.u(0.4, 0.6);
    let tx = -len / 2.0 + tcr * 1.1;
    let fin_h = len * r.u(0.12, 0.2);
    let t_tail = r.chance(0.25);
    let tz = if t_tail { fin_h } else { rad * 0.3 };
    for side in [-1.0f64, 1.0] {
        let flip = nalgebra::Matrix4::new_nonuniform_scaling(&nalgebra::Vector3::new(1.0, side, 1.0));
        s.add(plate(tcr, tcr * 0.5, tspan, tspan * 0.4, wing_t * 0.8), &(translate([tx, 0.0, tz]) * flip));
    }
    let fin = [[0.0, 0.0], [-tcr * 0.9, fin_h], [-tcr * 1.3, fin_h], [-tcr * 1.2, 0.0]];
    s.add(extrude(&fin, wing_t), &(translate([tx + tcr * 0.1, 0.0, rad * 0.5]) * side_view(wing_t / 2.0)));
    s.mesh
}

pub fn car(r: &mut Dice) -> Mesh {
    let mut s = Shape::default();
    let l = r.u(3.8, 5.2);
    let w = r.u(1.6, 2.0);
    let kind = r.int(0, 3); // sedan, hatchback, SUV, pickup
    let clear = r.u(0.12, 0.25) + if kind >= 2 { 0.1 } else { 0.0 };
    let bh = r.u(0.5, 0.7) + if kind >= 2 { 0.15 } else { 0.0 };
    let ch = r.u(0.4, 0.55);
    let hood = l * r.u(0.22, 0.32);
    let trunk = match kind {
        0 => l * r.u(0.15, 0.25),
        3 => l * r.u(0.3, 0.4),
        _ => l * r.u(0.02, 0.08),
    };
    let (x0, x1) = (-l / 2.0, l / 2.0);
    let z0 = clear;
    let z1 = clear + bh;
    let z2 = z1 + ch;
    // side-view outline (x, z), counter-clockwise from the rear bottom
    let ws = r.u(0.25, 0.45); // windshield slope run
    let rs = if kind == 1 || kind == 2 { r.u(0.05, 0.2) } else { r.u(0.25, 0.45) };
    let cabin_front = x1 - hood;
    let cabin_rear = x0 + trunk;
    let outline = if kind == 3 {
        // pickup: the body is cut down behind the cab; the bed is an open box
        let bed_l = cabin_rear - x0;
        for sy in [-1.0, 1.0] {
            s.add_at(slab([bed_l, 0.05, bh * 0.65]), [x0 + bed_l / 2.0, sy * (w / 2.0 - 0.025), z0 + bh * 0.35]);
        }
        s.add_at(slab([0.05, w, bh * 0.65]), [x0 + 0.025, 0.0, z0 + bh * 0.35]);
        vec![
            [x0 + 0.1, z0],
            [x1 - 0.15, z0],
            [x1, z0 + bh * 0.3],
            [x1 - 0.05, z1 - 0.05],
            [cabin_front, z1],
            [cabin_front - ws, z2],
            [cabin_rear + rs * 0.2, z2],
            [cabin_rear, z1],
            [cabin_rear, z0 + bh * 0.35],
            [x0, z0 + bh * 0.35],
            [x0, z0 + bh * 0.2],
        ]
    } else {
        vec![
            [x0 + 0.1, z0],
            [x1 - 0.15, z0],
            [x1, z0 + bh * 0.3],
            [x1 - 0.05, z1 - 0.05],
            [cabin_front, z1],
            [cabin_front - ws, z2],
            [cabin_rear + rs, z2],
            [cabin_rear, z1],
            [x0, z1 - 0.05],
            [x0, z0 + bh * 0.25],
        ]
    };
    s.add(extrude(&outline, w), &side_view(w / 2.0));
    // wheels along the y axis
    let wr = r.u(0.3, 0.4) + if kind >= 2 { 0.05 } else { 0.0 };
    let ww = r.u(0.18, 0.28);
    let wheelbase_f = x1 - hood * r.u(0.45, 0.65);
    let wheelbase_r = x0 + l * r.u(0.15, 0.22);
    for x in [wheelbase_f, wheelbase_r] {
        for sy in [-1.0f64, 1.0] {
            let y = sy * (w / 2.0 - ww * 0.4);
            s.add(cylinder(wr, ww, 16), &(translate([x, y - ww / 2.0, wr]) * rotate(0, -FRAC_PI_2)));
        }
    }
    // mirrors, lights, spoiler, roof rack
    for sy in [-1.0, 1.0] {
        s.add_at(cuboid([0.1, 0.15, 0.08]), [cabin_front - 0.1, sy * (w / 2.0 + 0.07), z1 + 0.1]);
        s.add_at(cuboid([0.04, 0.3, 0.1]), [x1 - 0.01, sy * w * 0.33, z0 + bh * 0.6]);
    }
    if kind == 0 && r.chance(0.3) {
        s.add_at(slab([0.2, w * 0.9, 0.04]), [x0 + 0.12, 0.0, z1 + 0.08]);
    }
    if kind == 2 && r.chance(0.5) {
        for sy in [-1.0, 1.0] {
            s.add_at(
                slab([(cabin_front - ws) - (cabin_rear + rs) - 0.2, 0.04, 0.05]),
                [((cabin_front - ws) + (cabin_rear + rs)) / 2.0, sy * w * 0.4, z2],
            );
        }
    }
    if kind == 1 && r.chance(0.5) {
        // a spare wheel on the back door
        s.add(cylinder(wr * 0.9, ww, 16), &(translate([x0, 0.0, z0 + bh * 0.7]) * rotate(1, -FRAC_PI_2)));
    }
    s.mesh
}
