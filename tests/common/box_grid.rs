//! A box's surface on a grid: a shape whose half turns about its axes fit it as well as the
//! truth (shared by the native tests through `common` and by the wasm tests by path).

/// Half-extents of the box: all different, so its only rigid symmetries are the half turns about
/// its three axes.
pub const BOX_HALF_EXTENTS: [f32; 3] = [1.0, 0.6, 0.35];

/// Points on the surface of the box of [`BOX_HALF_EXTENTS`], on a grid of `step` shifted by
/// `offset` along both directions of each face (two grids shifted apart sample the same surface
/// independently).
pub fn box_grid(step: f32, offset: f32) -> Vec<[f32; 3]> {
    let h = BOX_HALF_EXTENTS;
    let mut out = Vec::new();
    for k in 0..3 {
        let (a, b) = ((k + 1) % 3, (k + 2) % 3);
        for side in [-1.0f32, 1.0] {
            let mut u = -h[a] + offset;
            while u <= h[a] {
                let mut v = -h[b] + offset;
                while v <= h[b] {
                    let mut p = [0.0f32; 3];
                    (p[k], p[a], p[b]) = (side * h[k], u, v);
                    out.push(p);
                    v += step;
                }
                u += step;
            }
        }
    }
    out
}
