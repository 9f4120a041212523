//! Revolved objects: bottle, bowl, cone, cup, flower_pot, lamp. These categories are (nearly)
//! rotationally symmetric in reality; the parts that break the symmetry where real ones do
//! (a cup's handle, a traffic cone's square base, a plant, a desk lamp's arm) are included.

use super::parts::*;
use crate::io::Mesh;
use std::f64::consts::{FRAC_PI_2, PI};

/// A revolved wall of thickness `t` following the outer profile `outer` (radius, z), closed as a
/// loop: outer surface up, the rim, the inner surface back down.
fn shell(outer: &[(f64, f64)], t: f64, segments: usize) -> Mesh {
    let mut prof: Vec<(f64, f64)> = outer.to_vec();
    let mut inner: Vec<(f64, f64)> =
        outer.iter().skip(1).map(|&(r, z)| ((r - t).max(0.0), z.max(outer[0].1 + t))).collect();
    inner.reverse();
    prof.extend(inner);
    prof.push((0.0, outer[0].1 + t));
    lathe(&prof, segments, false)
}

pub fn bottle(r: &mut Dice) -> Mesh {
    let mut s = Shape::default();
    let rb = r.u(0.03, 0.06);
    let hb = r.u(0.1, 0.22);
    let rn = rb * r.u(0.25, 0.45);
    let hs = r.u(0.02, 0.08);
    let hn = r.u(0.03, 0.09);
    let waist = r.u(0.85, 1.0);
    let mut prof = vec![(0.0, 0.0), (rb * 0.92, 0.0), (rb, 0.01), (rb * waist, hb * 0.5), (rb, hb)];
    let steps = 5;
    for k in 1..=steps {
        let a = k as f64 / steps as f64 * FRAC_PI_2;
        prof.push((rn + (rb - rn) * a.cos(), hb + hs * a.sin()));
    }
    prof.push((rn, hb + hs + hn));
    let seg = r.pick(&[8, 12, 24, 32]);
    if r.chance(0.7) {
        // a cap
        prof.push((0.0, hb + hs + hn));
        s.add_at(lathe(&prof, seg, false), [0.0; 3]);
        s.add_at(cylinder(rn * 1.15, r.u(0.01, 0.03), seg), [0.0, 0.0, hb + hs + hn]);
    } else {
        prof.push((rn * 1.1, hb + hs + hn + 0.005));
        prof.push((0.0, hb + hs + hn + 0.005));
        s.add_at(lathe(&prof, seg, false), [0.0; 3]);
    }
    if r.chance(0.2) {
        // a jug handle
        let hr = hb * 0.3;
        s.add(
            torus(hr, rb * 0.12, PI, 12, 8),
            &(translate([rb * 0.9, 0.0, hb * 0.65]) * rotate(0, FRAC_PI_2) * rotate(2, -FRAC_PI_2)),
        );
    } else if r.chance(0.4) {
        // a label band, slightly proud, covering part of the circumference
        let a = r.u(1.5, 4.0);
        s.add(torus(rb, 0.003, a, 16, 4), &translate([0.0, 0.0, hb * r.u(0.3, 0.7)]));
    }
    s.mesh
}

pub fn bowl(r: &mut Dice) -> Mesh {
    let mut s = Shape::default();
    let rr = r.u(0.08, 0.2);
    let h = rr * r.u(0.35, 0.8);
    let rf = rr * r.u(0.3, 0.55);
    let fh = r.u(0.005, 0.02);
    let p = r.u(0.5, 1.5);
    let mut outer = vec![(0.0, 0.0), (rf, 0.0), (rf, fh)];
    let n = 8;
    for k in 1..=n {
        let u = k as f64 / n as f64;
        outer.push((rf + (rr - rf) * u.powf(p), fh + (h - fh) * u.sqrt()));
    }
    let t = r.u(0.004, 0.012);
    let seg = r.pick(&[16, 24, 32]);
    s.add_at(shell(&outer, t, seg), [0.0; 3]);
    if r.chance(0.3) {
        // two small lug handles
        for sx in [-1.0, 1.0] {
            s.add_at(cuboid([0.03, 0.04, 0.008]), [sx * (rr + 0.012), 0.0, h - 0.01]);
        }
    } else if r.chance(0.3) {
        // a spout
        s.add(frustum(0.015, 0.008, 0.05, 10), &(translate([rr * 0.95, 0.0, h * 0.85]) * rotate(1, 1.2)));
    }
    s.mesh
}

pub fn cone(r: &mut Dice) -> Mesh {
    let mut s = Shape::default();
    let h = r.u(0.3, 0.9);
    let rb = h * r.u(0.2, 0.4);
    let rt = rb * r.u(0.0, 0.2);
    let seg = r.pick(&[12, 16, 24, 32]);
    let base = r.chance(0.7);
    let bh = if base { r.u(0.02, 0.05) } else { 0.0 };
    if base {
        let bw = rb * r.u(2.1, 2.6);
        if r.chance(0.7) {
            s.add(slab([bw, bw, bh]), &rotate(2, r.u(0.0, 1.5)));
        } else {
            // octagonal base
            s.add_at(cylinder(bw * 0.55, bh, 8), [0.0; 3]);
        }
    }
    s.add_at(frustum(rb, rt, h, seg), [0.0, 0.0, bh]);
    for k in 0..r.int(0, 2) {
        // reflective bands
        let z = h * (0.45 + 0.25 * k as f64);
        let rz = rb + (rt - rb) * z / h;
        s.add_at(torus(rz, 0.004, 2.0 * PI, seg, 4), [0.0, 0.0, bh + z]);
    }
    s.mesh
}

pub fn cup(r: &mut Dice) -> Mesh {
    let mut s = Shape::default();
    let h = r.u(0.07, 0.14);
    let rt = r.u(0.035, 0.05);
    let rb = rt * r.u(0.65, 1.0);
    let t = r.u(0.003, 0.007);
    let n = 6;
    let bulge = r.u(0.0, 0.15);
    let mut outer = vec![(0.0, 0.0), (rb, 0.0)];
    for k in 1..=n {
        let u = k as f64 / n as f64;
        outer.push((rb + (rt - rb) * u + rt * bulge * (PI * u).sin(), h * u));
    }
    let seg = r.pick(&[16, 24, 32]);
    s.add_at(shell(&outer, t, seg), [0.0; 3]);
    // handle: a half torus on the +x side, in the xz plane
    let hr = h * r.u(0.25, 0.38);
    let tube = r.u(0.004, 0.008);
    s.add(
        torus(hr, tube, PI, 12, 8),
        &(translate([rt * (1.0 + bulge * 0.5) - 0.002, 0.0, h * 0.55]) * rotate(0, FRAC_PI_2) * rotate(2, -FRAC_PI_2)),
    );
    if r.chance(0.3) {
        // a saucer
        let sr = rt * r.u(1.6, 2.0);
        s.add_at(shell(&[(0.0, -0.012), (sr * 0.5, -0.012), (sr, -0.002)], 0.004, seg), [0.0; 3]);
    }
    s.mesh
}

pub fn flower_pot(r: &mut Dice) -> Mesh {
    let mut s = Shape::default();
    let h = r.u(0.12, 0.35);
    let rt = h * r.u(0.4, 0.7);
    let rb = rt * r.u(0.6, 0.9);
    let seg = if r.chance(0.2) { 4 } else { r.pick(&[12, 16, 24]) };
    let mut outer = vec![(0.0, 0.0), (rb, 0.0), (rt, h)];
    if r.chance(0.6) {
        // a rim
        outer.push((rt * 1.08, h));
        outer.push((rt * 1.08, h + h * 0.08));
    }
    let t = r.u(0.008, 0.015);
    s.add_at(shell(&outer, t, seg), [0.0; 3]);
    // soil
    s.add_at(cylinder(rt * 0.92, 0.005, seg), [0.0, 0.0, h * 0.85]);
    let top = h * 0.85;
    // the plant: a bush, a few stems with leaves, or a tall single stem
    match r.int(0, 2) {
        0 => {
            let bh = h * r.u(0.5, 1.6);
            s.add_at(
                ellipsoid([rt * r.u(0.5, 1.1), rt * r.u(0.5, 1.1), bh * 0.5], 14),
                [r.u(-0.2, 0.2) * rt, r.u(-0.2, 0.2) * rt, top + bh * 0.45],
            );
        }
        1 => {
            for _ in 0..r.int(3, 8) {
                let a = r.u(0.0, 2.0 * PI);
                let lean = r.u(0.1, 0.7);
                let len = h * r.u(0.6, 1.8);
                let tip = [len * lean.sin() * a.cos(), len * lean.sin() * a.sin(), top + len * lean.cos()];
                s.add_at(rod([0.0, 0.0, top], tip, 0.003, 6), [0.0; 3]);
                let leaf = ellipsoid([len * 0.25, len * 0.08, 0.004], 10);
                s.add(leaf, &(translate(tip) * rotate(2, a) * rotate(1, -lean)));
            }
        }
        _ => {
            let len = h * r.u(1.5, 3.0);
            let tip = [r.u(-0.1, 0.1) * len, r.u(-0.1, 0.1) * len, top + len];
            s.add_at(rod([0.0, 0.0, top], tip, 0.006, 8), [0.0; 3]);
            let br = len * r.u(0.08, 0.16);
            s.add_at(ellipsoid([br, br * r.u(0.7, 1.3), br * 0.8], 12), tip);
            // a few leaves along the stem
            for _ in 0..r.int(0, 4) {
                let f = r.u(0.2, 0.8);
                let at = [tip[0] * f, tip[1] * f, top + (tip[2] - top) * f];
                let leaf = ellipsoid([len * 0.12, len * 0.04, 0.004], 10);
                s.add(leaf, &(translate(at) * rotate(2, r.u(0.0, 2.0 * PI)) * rotate(1, -0.5)));
            }
        }
    }
    s.mesh
}

pub fn lamp(r: &mut Dice) -> Mesh {
    let mut s = Shape::default();
    let seg = r.pick(&[16, 24]);
    if r.chance(0.5) {
        // standing lamp: base, stem, shade
        let h = r.u(0.35, 1.6);
        let br = h * r.u(0.1, 0.2);
        s.add_at(cylinder(br, h * 0.03, seg), [0.0; 3]);
        let stem_top = h * 0.8;
        s.add_at(rod([0.0, 0.0, 0.0], [0.0, 0.0, stem_top], h * 0.012, 10), [0.0; 3]);
        let sh = h * r.u(0.18, 0.3);
        let sr0 = sh * r.u(0.7, 1.2);
        let sr1 = sr0 * r.u(0.45, 0.9);
        let t = 0.004;
        let prof = [(sr0, 0.0), (sr1, sh), (sr1 - t, sh), (sr0 - t, 0.0), (sr0, 0.0)];
        // the shade may be tilted (reading lamp)
        let tilt = if r.chance(0.3) { r.u(0.2, 0.6) } else { 0.0 };
        s.add(lathe(&prof, seg, false), &(translate([0.0, 0.0, stem_top - sh * 0.4]) * rotate(1, tilt)));
        if r.chance(0.5) {
            // a pull switch or a second arm to one side
            s.add_at(rod([0.0, 0.0, h * 0.5], [h * 0.15, 0.0, h * 0.6], h * 0.008, 6), [0.0; 3]);
        }
    } else {
        // desk lamp: base, two-segment arm, conical head
        let l1 = r.u(0.2, 0.4);
        let l2 = r.u(0.2, 0.4);
        let br = r.u(0.06, 0.1);
        if r.chance(0.5) {
            s.add_at(cylinder(br, 0.02, seg), [0.0; 3]);
        } else {
            s.add_at(slab([br * 2.0, br * 1.4, 0.02]), [0.0; 3]);
        }
        let a1 = r.u(0.1, 0.6);
        let j1 = [l1 * a1.sin(), 0.0, 0.02 + l1 * a1.cos()];
        let a2 = r.u(0.8, 1.8);
        let j2 = [j1[0] + l2 * a2.sin(), 0.0, j1[2] + l2 * a2.cos()];
        s.add_at(rod([0.0, 0.0, 0.02], j1, 0.008, 8), [0.0; 3]);
        s.add_at(rod(j1, j2, 0.008, 8), [0.0; 3]);
        s.add_at(ellipsoid([0.015, 0.015, 0.015], 8), j1);
        let hl = r.u(0.08, 0.15);
        let head = frustum(0.02, hl * 0.6, hl, seg);
        s.add(head, &(translate(j2) * rotate(1, PI - r.u(0.0, 0.7))));
        if r.chance(0.5) {
            // a spring alongside the lower arm
            s.add_at(rod([0.02, 0.02, 0.05], [j1[0] * 0.8 + 0.02, 0.02, j1[2] * 0.8], 0.004, 6), [0.0; 3]);
        }
    }
    s.mesh
}
