//! Furniture: bathtub, bed, bench, bookshelf, chair, desk, door, dresser. z is up, x is the
//! width, the front faces -y. Each shape gets at least one part that breaks its mirror
//! symmetries (a faucet, a headboard, books, a pedestal, a handle ...), as real ones usually do.

use super::parts::*;
use crate::io::Mesh;

/// Four legs under a rectangle `w` x `d` at height `h` (`[w, d, h]` = `size`, inset `inset`),
/// round or square, splayed outwards by `splay` at the floor.
fn legs(s: &mut Shape, r: &mut Dice, size: [f64; 3], inset: f64, thick: f64, splay: f64) {
    let [w, d, h] = size;
    let round = r.chance(0.5);
    for sx in [-1.0, 1.0] {
        for sy in [-1.0, 1.0] {
            let top = [sx * (w / 2.0 - inset), sy * (d / 2.0 - inset), h];
            let bot = [top[0] + sx * splay, top[1] + sy * splay, 0.0];
            let leg = if round { rod(bot, top, thick / 2.0, 8) } else { beam(bot, top, thick) };
            s.add_at(leg, [0.0; 3]);
        }
    }
}

pub fn bathtub(r: &mut Dice) -> Mesh {
    let mut s = Shape::default();
    let (l, w, h) = (r.u(1.4, 1.9), r.u(0.65, 0.9), r.u(0.45, 0.65));
    let t = r.u(0.04, 0.09);
    let z0 = if r.chance(0.4) {
        // claw feet
        let fh = r.u(0.06, 0.15);
        for sx in [-1.0, 1.0] {
            for sy in [-1.0, 1.0] {
                s.add_at(ellipsoid([0.05, 0.05, fh * 0.5], 10), [sx * l * 0.38, sy * w * 0.35, fh * 0.5]);
            }
        }
        fh
    } else {
        0.0
    };
    if r.chance(0.5) {
        s.add_at(open_box([l, w, h], t), [0.0, 0.0, z0]);
    } else {
        // rounded tub: a lathe wall squashed into an oval
        let prof = [(0.0, 0.0), (0.42, 0.0), (0.5, h), (0.5 - t, h), (0.42 - t, t), (0.0, t)];
        let tub =
            linear(lathe(&prof, 28, false), &nalgebra::Matrix3::from_diagonal(&nalgebra::Vector3::new(l, w, 1.0)));
        s.add_at(tub, [0.0, 0.0, z0]);
    }
    // faucet at one end, off-centre
    let fx = -l / 2.0 + t * 0.5;
    let fy = r.u(-0.15, 0.15) * w;
    let top = z0 + h + r.u(0.12, 0.25);
    s.add_at(rod([fx, fy, z0 + h * 0.6], [fx, fy, top], 0.02, 8), [0.0; 3]);
    s.add_at(rod([fx, fy, top], [fx + r.u(0.12, 0.2), fy, top], 0.018, 8), [0.0; 3]);
    if r.chance(0.5) {
        // headrest at the other end
        s.add_at(cuboid([0.06, w * 0.4, 0.15]), [l / 2.0 - t - 0.05, 0.0, z0 + h - 0.1]);
    }
    s.mesh
}

pub fn bed(r: &mut Dice) -> Mesh {
    let mut s = Shape::default();
    let (l, w) = (r.u(1.9, 2.2), r.pick(&[0.9, 1.2, 1.4, 1.6, 1.8]) * r.u(0.95, 1.05));
    let fh = r.u(0.15, 0.35);
    let frame_t = r.u(0.08, 0.2);
    legs(&mut s, r, [l, w, fh], 0.05, 0.06, 0.0);
    s.add_at(slab([l, w, frame_t]), [0.0, 0.0, fh]);
    let mt = r.u(0.15, 0.3);
    s.add_at(slab([l * 0.97, w * 0.96, mt]), [0.0, 0.0, fh + frame_t]);
    // headboard at -x, taller than the footboard
    let hb = r.u(0.5, 1.0);
    let ht = r.u(0.04, 0.1);
    s.add_at(slab([ht, w, fh + hb]), [-l / 2.0 - ht / 2.0, 0.0, 0.0]);
    if r.chance(0.5) {
        s.add_at(slab([ht, w, fh + hb * r.u(0.3, 0.6)]), [l / 2.0 + ht / 2.0, 0.0, 0.0]);
    }
    let top = fh + frame_t + mt;
    let pillows = if w > 1.1 { r.int(1, 2) } else { 1 };
    for k in 0..pillows {
        let y = if pillows == 1 { 0.0 } else { (k as f64 - 0.5) * w * 0.5 };
        s.add_at(ellipsoid([0.2, (w / pillows as f64) * 0.4, 0.07], 14), [-l / 2.0 + 0.3, y, top + 0.05]);
    }
    if r.chance(0.4) {
        // a folded blanket across the foot end
        s.add_at(slab([l * 0.3, w * 0.98, 0.05]), [l * 0.25, 0.0, top]);
    }
    s.mesh
}

pub fn bench(r: &mut Dice) -> Mesh {
    let mut s = Shape::default();
    let (l, d, h) = (r.u(1.0, 2.0), r.u(0.3, 0.5), r.u(0.4, 0.5));
    let st = r.u(0.03, 0.08);
    if r.chance(0.5) {
        let splay = r.u(0.0, 0.05);
        legs(&mut s, r, [l, d, h], 0.08, 0.05, splay);
    } else {
        // two slab legs
        for sx in [-1.0, 1.0] {
            s.add_at(slab([0.05, d * 0.9, h]), [sx * (l / 2.0 - 0.12), 0.0, 0.0]);
        }
    }
    if r.chance(0.5) {
        s.add_at(slab([l, d, st]), [0.0, 0.0, h]);
    } else {
        // slats
        let n = r.int(3, 5);
        for k in 0..n {
            let y = -d / 2.0 + d * (k as f64 + 0.5) / n as f64;
            s.add_at(slab([l, d / n as f64 * 0.75, st]), [0.0, y, h]);
        }
    }
    if r.chance(0.6) {
        // backrest at +y, tilted
        let bh = r.u(0.3, 0.5);
        let tilt = r.u(0.0, 0.3);
        s.add(slab([l, 0.04, bh]), &(translate([0.0, d / 2.0, h + st]) * rotate(0, -tilt)));
        if r.chance(0.5) {
            for sx in [-1.0, 1.0] {
                s.add_at(slab([0.05, d, 0.04]), [sx * (l / 2.0 - 0.025), 0.0, h + 0.25]);
                s.add_at(slab([0.04, 0.04, 0.25]), [sx * (l / 2.0 - 0.025), -d / 2.0 + 0.03, h]);
            }
        }
    } else {
        // a bag or cushion on one end
        s.add_at(ellipsoid([0.15, d * 0.35, 0.07], 12), [-l / 2.0 + 0.25, 0.0, h + st + 0.05]);
    }
    s.mesh
}

pub fn bookshelf(r: &mut Dice) -> Mesh {
    let mut s = Shape::default();
    let (w, d, h) = (r.u(0.6, 1.6), r.u(0.25, 0.4), r.u(0.8, 2.0));
    let t = r.u(0.015, 0.04);
    for sx in [-1.0, 1.0] {
        s.add_at(slab([t, d, h]), [sx * (w - t) / 2.0, 0.0, 0.0]);
    }
    if r.chance(0.8) {
        s.add_at(slab([w, t, h]), [0.0, (d - t) / 2.0, 0.0]);
    }
    let shelves = r.int(2, 6);
    let gap = h / shelves as f64;
    for k in 0..=shelves {
        let z = (k as f64 * gap).min(h - t);
        s.add_at(slab([w - 2.0 * t, d, t]), [0.0, 0.0, z]);
        if k == shelves {
            break;
        }
        // books on this shelf: random runs, leaning book at the end
        let mut x = -w / 2.0 + t + r.u(0.0, 0.1);
        let end = w / 2.0 - t - 0.03;
        let fill = r.u(0.2, 0.95);
        while x < -w / 2.0 + t + (w - 2.0 * t) * fill && x < end {
            let bw = r.u(0.02, 0.06);
            let bh = (gap - t) * r.u(0.55, 0.9);
            let bd = d * r.u(0.6, 0.9);
            s.add_at(slab([bw, bd, bh]), [x + bw / 2.0, -d / 2.0 + bd / 2.0 + 0.01, z + t]);
            x += bw + if r.chance(0.1) { 0.05 } else { 0.002 };
        }
        if r.chance(0.3) && x + 0.1 < end {
            let bh = (gap - t) * 0.7;
            s.add(slab([0.03, d * 0.7, bh]), &(translate([x + 0.05, -d * 0.1, z + t]) * rotate(1, 0.35)));
        }
    }
    s.mesh
}

pub fn chair(r: &mut Dice) -> Mesh {
    let mut s = Shape::default();
    let (w, d, h) = (r.u(0.4, 0.6), r.u(0.4, 0.55), r.u(0.4, 0.5));
    let st = r.u(0.03, 0.1);
    let swivel = r.chance(0.25);
    if swivel {
        let n = r.int(4, 5);
        for k in 0..n {
            let a = std::f64::consts::TAU * k as f64 / n as f64;
            let e = [0.3 * a.cos(), 0.3 * a.sin(), 0.06];
            s.add_at(beam([0.0, 0.0, 0.08], e, 0.04), [0.0; 3]);
            s.add_at(ellipsoid([0.03, 0.03, 0.03], 8), [e[0], e[1], 0.03]);
        }
        s.add_at(cylinder(0.03, h - 0.08, 10), [0.0, 0.0, 0.08]);
    } else {
        let (thick, splay) = (r.u(0.025, 0.05), r.u(0.0, 0.04));
        legs(&mut s, r, [w, d, h], 0.04, thick, splay);
        if r.chance(0.4) {
            // a stretcher between the front legs only
            s.add_at(
                beam([-w / 2.0 + 0.04, -d / 2.0 + 0.04, 0.15], [w / 2.0 - 0.04, -d / 2.0 + 0.04, 0.15], 0.02),
                [0.0; 3],
            );
        }
    }
    s.add_at(slab([w, d, st]), [0.0, 0.0, h]);
    // backrest at +y
    let bh = r.u(0.35, 0.7);
    let tilt = r.u(0.0, 0.25);
    let back = translate([0.0, d / 2.0, h + st]) * rotate(0, -tilt);
    match r.int(0, 2) {
        0 => s.add(slab([w, 0.03, bh]), &back),
        1 => {
            // two posts and rails
            for sx in [-1.0, 1.0] {
                s.add(slab([0.03, 0.03, bh]), &(back * translate([sx * (w / 2.0 - 0.015), 0.0, 0.0])));
            }
            let rails = r.int(1, 4);
            for k in 0..rails {
                let z = bh * (1.0 - 0.22 * k as f64) - 0.06;
                s.add(slab([w, 0.025, 0.05]), &(back * translate([0.0, 0.0, z])));
            }
        }
        _ => {
            // rounded padded back
            s.add(ellipsoid([w * 0.5, 0.05, bh * 0.5], 16), &(back * translate([0.0, 0.0, bh * 0.5])));
        }
    }
    if r.chance(0.4) {
        let ah = r.u(0.18, 0.28);
        for sx in [-1.0, 1.0] {
            let x = sx * (w / 2.0 + 0.02);
            s.add_at(slab([0.04, d * 0.9, 0.03]), [x, 0.0, h + st + ah]);
            s.add_at(slab([0.03, 0.03, ah]), [x, -d * 0.35, h + st]);
        }
    }
    s.mesh
}

pub fn desk(r: &mut Dice) -> Mesh {
    let mut s = Shape::default();
    let (w, d, h) = (r.u(1.0, 1.8), r.u(0.5, 0.8), r.u(0.7, 0.78));
    let tt = r.u(0.025, 0.05);
    let side = r.sign();
    // a drawer pedestal on one side, legs or a panel on the other
    let pw = r.u(0.35, 0.5);
    let px = side * (w / 2.0 - pw / 2.0);
    s.add_at(slab([pw, d * 0.95, h - tt]), [px, 0.0, 0.0]);
    let drawers = r.int(2, 4);
    for k in 0..drawers {
        let dh = (h - tt) / drawers as f64;
        let z = k as f64 * dh;
        s.add_at(slab([pw * 0.9, 0.015, dh * 0.85]), [px, -d * 0.475 - 0.007, z + dh * 0.075]);
        s.add_at(cuboid([0.08, 0.02, 0.015]), [px, -d * 0.475 - 0.022, z + dh * 0.7]);
    }
    let ox = -side * (w / 2.0 - 0.03);
    if r.chance(0.5) {
        s.add_at(slab([0.04, d * 0.95, h - tt]), [ox, 0.0, 0.0]);
    } else {
        for sy in [-1.0, 1.0] {
            s.add_at(beam([ox, sy * (d / 2.0 - 0.04), 0.0], [ox, sy * (d / 2.0 - 0.04), h - tt], 0.05), [0.0; 3]);
        }
    }
    if r.chance(0.6) {
        // modesty panel at the back
        s.add_at(slab([w - pw - 0.05, 0.02, (h - tt) * 0.5]), [-side * pw / 2.0, d / 2.0 - 0.03, (h - tt) * 0.45]);
    }
    s.add_at(slab([w, d, tt]), [0.0, 0.0, h - tt]);
    if r.chance(0.4) {
        // a hutch shelf on top at the back
        let hh = r.u(0.25, 0.5);
        s.add_at(slab([w, 0.25, 0.02]), [0.0, d / 2.0 - 0.125, h + hh]);
        for sx in [-1.0, 1.0] {
            s.add_at(slab([0.02, 0.25, hh]), [sx * (w / 2.0 - 0.01), d / 2.0 - 0.125, h]);
        }
    }
    if r.chance(0.4) {
        // a monitor or lamp on the desk
        s.add_at(slab([0.5, 0.04, 0.3]), [r.u(-0.3, 0.3) * w, d * 0.2, h + 0.1]);
        s.add_at(slab([0.05, 0.05, 0.1]), [0.0, d * 0.2, h]);
    }
    s.mesh
}

pub fn door(r: &mut Dice) -> Mesh {
    let mut s = Shape::default();
    let (w, h, t) = (r.u(0.7, 1.0), r.u(1.9, 2.2), r.u(0.035, 0.06));
    // the leaf, in the xz plane, thickness along y
    s.add_at(slab([w, t, h]), [0.0, 0.0, 0.0]);
    // raised panels
    let cols = r.int(1, 2);
    let rows = r.int(1, 4);
    let (mw, mh) = (w * 0.12, h * 0.08);
    let pw = (w - 2.0 * mw - (cols - 1) as f64 * mw) / cols as f64;
    let ph = (h - 2.0 * mh - (rows - 1) as f64 * mh) / rows as f64;
    let glass_row = if r.chance(0.3) { Some(rows - 1) } else { None };
    for i in 0..cols {
        for j in 0..rows {
            let x = -w / 2.0 + mw + i as f64 * (pw + mw) + pw / 2.0;
            let z = mh + j as f64 * (ph + mh);
            if glass_row == Some(j) {
                continue; // a glazed (flush) panel
            }
            for sy in [-1.0, 1.0] {
                s.add_at(slab([pw, 0.012, ph]), [x, sy * (t / 2.0 + 0.006), z]);
            }
        }
    }
    // handle on one side: a lever or knob, both faces
    let side = r.sign();
    let hx = side * (w / 2.0 - r.u(0.06, 0.1));
    let hz = r.u(0.95, 1.1);
    let lever = r.chance(0.5);
    for sy in [-1.0, 1.0] {
        let y = sy * t / 2.0;
        if lever {
            s.add_at(rod([hx, y, hz], [hx, y + sy * 0.06, hz], 0.012, 8), [0.0; 3]);
            s.add_at(rod([hx, y + sy * 0.06, hz], [hx - side * 0.13, y + sy * 0.06, hz], 0.01, 8), [0.0; 3]);
        } else {
            s.add_at(ellipsoid([0.03, 0.03, 0.03], 10), [hx, y + sy * 0.05, hz]);
            s.add_at(rod([hx, y, hz], [hx, y + sy * 0.04, hz], 0.01, 8), [0.0; 3]);
        }
    }
    // hinges on the other side
    for z in [0.2, h - 0.2] {
        s.add_at(cylinder(0.012, 0.1, 8), [-side * (w / 2.0 + 0.01), 0.0, z]);
    }
    if r.chance(0.5) {
        // a frame
        let f = r.u(0.05, 0.1);
        let ft = t * r.u(1.5, 3.0);
        for sx in [-1.0, 1.0] {
            s.add_at(slab([f, ft, h + f]), [sx * (w / 2.0 + f / 2.0 + 0.01), 0.0, 0.0]);
        }
        s.add_at(slab([w + 2.0 * f + 0.02, ft, f]), [0.0, 0.0, h + 0.01]);
    }
    s.mesh
}

pub fn dresser(r: &mut Dice) -> Mesh {
    let mut s = Shape::default();
    let (w, d, h) = (r.u(0.6, 1.6), r.u(0.4, 0.6), r.u(0.7, 1.4));
    let lh = if r.chance(0.6) { r.u(0.05, 0.15) } else { 0.0 };
    if lh > 0.0 {
        legs(&mut s, r, [w, d, lh], 0.04, 0.04, 0.0);
    }
    s.add_at(slab([w, d, h - lh]), [0.0, 0.0, lh]);
    s.add_at(slab([w + 0.03, d + 0.03, 0.03]), [0.0, 0.0, h]);
    // drawer grid: rows, some split in two columns, one column of doors sometimes
    let rows = r.int(3, 6);
    let rh = (h - lh - 0.04) / rows as f64;
    for k in 0..rows {
        let z = lh + 0.02 + k as f64 * rh;
        let split = if k + 1 == rows { r.chance(0.7) } else { r.chance(0.3) };
        let cols = if split { 2 } else { 1 };
        let cw = (w - 0.04) / cols as f64;
        for c in 0..cols {
            let x = -w / 2.0 + 0.02 + cw * (c as f64 + 0.5);
            s.add_at(slab([cw - 0.02, 0.02, rh - 0.02]), [x, -d / 2.0 - 0.01, z + 0.01]);
            let kn = if cw > 0.5 { [-cw * 0.25, cw * 0.25].to_vec() } else { vec![0.0] };
            for dx in kn {
                s.add_at(ellipsoid([0.018, 0.025, 0.018], 8), [x + dx, -d / 2.0 - 0.03, z + rh * 0.55]);
            }
        }
    }
    if r.chance(0.35) {
        // a mirror at the back
        let mh = r.u(0.5, 0.9);
        let mw = w * r.u(0.5, 0.9);
        s.add_at(slab([mw, 0.03, mh]), [r.u(-0.1, 0.1) * w, d / 2.0 - 0.05, h + 0.03]);
    } else if r.chance(0.5) {
        // something on top: a box or a vase at one end
        s.add_at(frustum(0.06, 0.04, r.u(0.15, 0.3), 12), [r.sign() * w * 0.35, 0.0, h + 0.03]);
    }
    s.mesh
}
