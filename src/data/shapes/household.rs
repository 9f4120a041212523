//! Household objects: curtain, glass_box, guitar, keyboard.

use super::parts::*;
use crate::io::Mesh;
use std::f64::consts::{FRAC_PI_2, TAU};

/// A folded sheet hanging from z = `h` down to 0: a thick wave across x, extruded along z.
fn folds(width: f64, h: f64, amp: f64, wavelength: f64, t: f64, phase: f64) -> Mesh {
    let n = ((width / wavelength) * 8.0).ceil().max(8.0) as usize;
    let y = |x: f64| amp * (TAU * x / wavelength + phase).sin();
    let mut outline: Vec<[f64; 2]> = (0..=n)
        .map(|i| {
            let x = width * i as f64 / n as f64;
            [x, y(x)]
        })
        .collect();
    outline.extend((0..=n).rev().map(|i| {
        let x = width * i as f64 / n as f64;
        [x, y(x) + t]
    }));
    extrude(&outline, h)
}

pub fn curtain(r: &mut Dice) -> Mesh {
    let mut s = Shape::default();
    let w = r.u(1.0, 2.5);
    let h = r.u(1.2, 2.4);
    let t = r.u(0.01, 0.02);
    // the rod with finials at the top
    let rod_r = r.u(0.01, 0.02);
    s.add_at(rod([-w / 2.0 - 0.1, 0.0, h + 0.05], [w / 2.0 + 0.1, 0.0, h + 0.05], rod_r, 10), [0.0; 3]);
    for sx in [-1.0, 1.0] {
        s.add_at(ellipsoid([0.03, 0.03, 0.03], 8), [sx * (w / 2.0 + 0.12), 0.0, h + 0.05]);
    }
    // one or two panels of different widths, drops and fold frequencies
    let panels = r.int(1, 2);
    let split = if panels == 2 { r.u(0.3, 0.7) } else { 1.0 };
    let mut x0 = -w / 2.0;
    for k in 0..panels {
        let pw = if k == 0 { w * split } else { w * (1.0 - split) };
        let gathered = r.chance(0.35);
        let (pw_eff, amp, wl) = if gathered {
            (pw * r.u(0.3, 0.6), r.u(0.05, 0.1), r.u(0.06, 0.12))
        } else {
            (pw, r.u(0.02, 0.07), r.u(0.1, 0.3))
        };
        let drop = h * r.u(0.75, 1.0);
        let px = if gathered && k == 0 { x0 } else { x0 + pw - pw_eff };
        let xf = translate([px, 0.0, h - drop]);
        s.add(folds(pw_eff, drop, amp, wl, t, r.u(0.0, TAU)), &xf);
        if gathered && r.chance(0.6) {
            // a tie-back band
            s.add_at(slab([pw_eff + 0.02, 2.0 * amp + 0.04, 0.04]), [px + pw_eff / 2.0, 0.0, h - drop + drop * 0.4]);
        }
        x0 += pw;
    }
    if r.chance(0.3) {
        // a valance across the top
        s.add(folds(w, h * 0.15, 0.03, 0.15, t, 0.0), &translate([-w / 2.0, -0.08, h * 0.87]));
    }
    s.mesh
}

pub fn glass_box(r: &mut Dice) -> Mesh {
    let mut s = Shape::default();
    let (w, d, h) = (r.u(0.4, 1.2), r.u(0.3, 0.6), r.u(0.3, 1.8));
    let f = r.u(0.01, 0.03);
    let g = 0.006;
    let z0 = if r.chance(0.4) {
        // a cabinet stand
        let sh = r.u(0.2, 0.8);
        s.add_at(slab([w, d, sh]), [0.0; 3]);
        s.add_at(cuboid([0.1, 0.02, 0.015]), [w * 0.25, -d / 2.0 - 0.01, sh * 0.8]);
        sh
    } else {
        0.0
    };
    // frame: the 12 edges
    for sx in [-1.0, 1.0] {
        for sy in [-1.0, 1.0] {
            let (x, y) = (sx * (w - f) / 2.0, sy * (d - f) / 2.0);
            s.add_at(beam([x, y, z0], [x, y, z0 + h], f), [0.0; 3]);
        }
        for z in [z0 + f / 2.0, z0 + h - f / 2.0] {
            s.add_at(beam([sx * (w - f) / 2.0, -d / 2.0, z], [sx * (w - f) / 2.0, d / 2.0, z], f), [0.0; 3]);
            s.add_at(beam([-w / 2.0, sx * (d - f) / 2.0, z], [w / 2.0, sx * (d - f) / 2.0, z], f), [0.0; 3]);
        }
    }
    // glass panes on the sides, top and bottom; the back may be opaque
    for sx in [-1.0, 1.0] {
        s.add_at(slab([g, d - f, h - f]), [sx * (w - f) / 2.0, 0.0, z0 + f / 2.0]);
        s.add_at(slab([w - f, g, h - f]), [0.0, sx * (d - f) / 2.0, z0 + f / 2.0]);
    }
    s.add_at(slab([w, d, g]), [0.0, 0.0, z0]);
    if r.chance(0.7) {
        s.add_at(slab([w, d, g]), [0.0, 0.0, z0 + h - g]);
    }
    // inside: glass shelves, or water and stones (an aquarium), or an object on display
    match r.int(0, 2) {
        0 => {
            for k in 1..r.int(1, 4) {
                let z = z0 + h * k as f64 / 4.0;
                s.add_at(slab([w - 2.0 * f, d - 2.0 * f, g]), [0.0, 0.0, z]);
            }
        }
        1 => {
            for _ in 0..r.int(2, 6) {
                let sr = r.u(0.02, 0.06);
                s.add_at(
                    ellipsoid([sr * 1.5, sr, sr * 0.7], 10),
                    [r.u(-0.4, 0.4) * w, r.u(-0.35, 0.35) * d, z0 + sr * 0.5],
                );
            }
        }
        _ => {
            let oh = h * r.u(0.3, 0.6);
            s.add_at(frustum(w * 0.12, w * 0.06, oh, 12), [r.u(-0.2, 0.2) * w, 0.0, z0]);
        }
    }
    // a handle on the front pane, to one side
    s.add_at(cuboid([0.015, 0.02, h * 0.2]), [r.sign() * w * 0.35, -d / 2.0 - 0.01, z0 + h * 0.5]);
    s.mesh
}

pub fn guitar(r: &mut Dice) -> Mesh {
    let mut s = Shape::default();
    let acoustic = r.chance(0.5);
    let l = if acoustic { r.u(0.45, 0.52) } else { r.u(0.38, 0.45) };
    let wl = l * r.u(0.3, 0.36); // lower-bout half width
    let wu = wl * r.u(0.7, 0.85);
    let (c1, a1) = (l * 0.3, l * 0.3);
    let (c2, a2) = (l * 0.74, l * 0.26);
    // electric bodies get an asymmetric cutaway on one side
    let cut = if acoustic { 1.0 } else { r.u(0.4, 0.75) };
    let half = |y: f64, upper_scale: f64| {
        let e = |c: f64, a: f64, w: f64| {
            let q = 1.0 - ((y - c) / a).powi(2);
            if q > 0.0 {
                w * q.sqrt()
            } else {
                0.0
            }
        };
        e(c1, a1, wl).max(e(c2, a2 * upper_scale, wu))
    };
    let n = 40;
    let ys: Vec<f64> = (1..n).map(|i| l * i as f64 / n as f64).collect();
    let mut outline: Vec<[f64; 2]> = vec![[0.0, 0.0]];
    outline.extend(ys.iter().map(|&y| [half(y, 1.0).max(0.002), y]));
    outline.push([0.0, l]);
    outline.extend(ys.iter().rev().map(|&y| [-half(y, cut).max(0.002), y]));
    let depth = if acoustic { r.u(0.08, 0.12) } else { r.u(0.035, 0.05) };
    s.add_at(extrude(&outline, depth), [0.0; 3]);
    // neck, fretboard side up (+z)
    let nl = r.u(0.42, 0.5);
    let nw = r.u(0.045, 0.055);
    s.add_at(slab([nw, nl, 0.025]), [0.0, l - 0.02 + nl / 2.0, depth - 0.01]);
    // headstock, tilted back, with pegs
    let hl = r.u(0.15, 0.2);
    let tilt = if acoustic { r.u(0.1, 0.25) } else { 0.0 };
    let hs = translate([0.0, l - 0.02 + nl, depth - 0.01]) * rotate(0, -tilt);
    s.add(slab([nw * 1.5, hl, 0.018]), &(hs * translate([0.0, hl / 2.0, 0.0])));
    let inline6 = !acoustic && r.chance(0.5);
    for k in 0..6 {
        let (x, y) = if inline6 {
            (nw * 0.75 + 0.01, hl * (0.15 + 0.13 * k as f64))
        } else {
            let side = if k < 3 { -1.0 } else { 1.0 };
            (side * (nw * 0.75 + 0.01), hl * (0.25 + 0.25 * (k % 3) as f64))
        };
        s.add(rod([0.0, 0.0, 0.0], [x.signum() * 0.025, 0.0, 0.0], 0.004, 6), &(hs * translate([x, y, 0.009])));
    }
    // bridge, and a sound hole ring or pickups
    s.add_at(slab([wl * 0.6, 0.02, 0.01]), [0.0, c1 * 0.8, depth]);
    if acoustic {
        s.add_at(torus(wu * 0.45, 0.004, TAU, 24, 4), [0.0, c2 * 0.85, depth]);
    } else {
        for k in 0..r.int(1, 3) {
            s.add_at(slab([nw * 1.4, 0.03, 0.008]), [0.0, c1 + 0.05 + 0.06 * k as f64, depth]);
        }
        // knobs on the lower bout, to one side
        for k in 0..r.int(2, 4) {
            s.add_at(cylinder(0.01, 0.015, 8), [wl * 0.55, c1 * (0.5 + 0.25 * k as f64), depth]);
        }
    }
    // strap button at the bottom end
    s.add(cylinder(0.006, 0.012, 8), &(rotate(0, FRAC_PI_2) * translate([0.0, depth / 2.0, 0.0])));
    s.mesh
}

pub fn keyboard(r: &mut Dice) -> Mesh {
    let mut s = Shape::default();
    let key = r.u(0.016, 0.02);
    let gap = key * r.u(0.12, 0.25);
    let pitch = key + gap;
    let cols = r.int(13, 15);
    let rows = r.int(5, 6);
    let numpad = r.chance(0.6);
    let arrows = numpad || r.chance(0.5);
    let main_w = cols as f64 * pitch;
    let extra_w = if numpad {
        4.0 * pitch + 3.5 * pitch
    } else if arrows {
        3.5 * pitch
    } else {
        0.0
    };
    let margin = r.u(0.01, 0.03);
    let w = main_w + extra_w + 2.0 * margin;
    let d = rows as f64 * pitch + 2.0 * margin;
    let bt = r.u(0.012, 0.025);
    // the base, wedge-shaped: thicker at the back (+y)
    let back = bt * r.u(1.2, 2.0);
    let wedge = [[-d / 2.0, 0.0], [d / 2.0, 0.0], [d / 2.0, back], [-d / 2.0, bt]];
    // extruded (y, z) profile along x: (a, b, c) -> (x, y, z) = (c - w/2, a, b)
    #[rustfmt::skip]
    let yz_to_x = nalgebra::Matrix4::new(
        0.0, 0.0, 1.0, -w / 2.0,
        1.0, 0.0, 0.0, 0.0,
        0.0, 1.0, 0.0, 0.0,
        0.0, 0.0, 0.0, 1.0,
    );
    s.add(extrude(&wedge, w), &yz_to_x);
    let top = |y: f64| bt + (back - bt) * (y + d / 2.0) / d;
    let kh = r.u(0.006, 0.01);
    let x0 = -w / 2.0 + margin;
    let y0 = -d / 2.0 + margin;
    let put = |s: &mut Shape, x: f64, y: f64, kw: f64| {
        s.add_at(slab([kw, key, kh]), [x + kw / 2.0, y + key / 2.0, top(y + key / 2.0)]);
    };
    for j in 0..rows {
        let y = y0 + j as f64 * pitch;
        if j == 0 {
            // bottom row: modifiers and a space bar
            let mut x = x0;
            let sb = r.int(5, 7);
            for k in 0..cols.saturating_sub(sb) + 1 {
                if k == 3 {
                    let kw = sb as f64 * pitch - gap;
                    put(&mut s, x, y, kw);
                    x += sb as f64 * pitch;
                } else {
                    put(&mut s, x, y, key);
                    x += pitch;
                }
                if x > x0 + main_w - pitch * 0.5 {
                    break;
                }
            }
            continue;
        }
        let offset = (j as f64 * 0.25).fract() * pitch;
        let mut x = x0 + offset;
        while x + key <= x0 + main_w + 1e-9 {
            put(&mut s, x, y, key);
            x += pitch;
        }
    }
    let mut ex = x0 + main_w + 0.5 * pitch;
    if arrows {
        let y = y0;
        for i in 0..3 {
            put(&mut s, ex + i as f64 * pitch, y, key);
        }
        put(&mut s, ex + pitch, y + pitch, key);
        ex += 3.5 * pitch;
    }
    if numpad {
        for j in 0..rows.min(5) {
            for i in 0..4 {
                if j == 0 && i == 1 {
                    continue;
                }
                let kw = if j == 0 && i == 0 { 2.0 * pitch - gap } else { key };
                put(&mut s, ex + i as f64 * pitch, y0 + j as f64 * pitch, kw);
            }
        }
    }
    if r.chance(0.5) {
        // a cable leaving the back edge
        let cx = r.u(-0.3, 0.3) * w;
        s.add_at(
            rod([cx, d / 2.0, back * 0.5], [cx + r.u(-0.05, 0.05), d / 2.0 + r.u(0.05, 0.15), back * 0.3], 0.003, 6),
            [0.0; 3],
        );
    }
    s.mesh
}
