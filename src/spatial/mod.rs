//! A small exact nearest-neighbour index over `f32` xyz points (a static k-d tree), built once
//! and queried many times by ICP and normal estimation.
//!
//! Why not a crate: the ICP hot loop needs a nearest-neighbour query that is *bounded* by the
//! max correspondence distance and can be *warm-started* from the previous iteration's partner,
//! without allocating. `kiddo` 6 (which builds for wasm32 with `default-features = false`) was
//! tried first: its plain nearest-one query measured about 1.6x slower than this tree on an
//! 11k-point scan, a bounded nearest-one goes through `nearest_n(1).within(..)`, which returns a
//! `Vec`, and it brings a build script that tunes the code to the *build* machine's cache line
//! size, plus `tracing` and proc-macro dependencies. This tree is ~200 lines, has no
//! dependencies, and is deterministic (same points, same tree, same answers); its only `unsafe` is
//! the traversal stack's, left uninitialised (`Stack`).
//!
//! Layout: points are reordered so that every leaf is a contiguous run of positions starting at a
//! multiple of four, stored four points to a chunk, coordinate by coordinate (`chunk.rs`: a leaf's
//! scan computes four distances at once, in WebAssembly's 128-bit SIMD); nodes split the widest
//! axis of their points' bounding box at the median (`select_nth_unstable`), so the depth is at
//! most `log2(n / LEAF) + 1`; leaves hold at most [`LEAF`] points. Queries descend
//! iteratively with a fixed-size stack, pruning subtrees by the incremental query-to-cell
//! distance (Arya & Mount) and, in the bounded nearest search, by each node's tight bounding box;
//! a hinted nearest search first tries the hint's own nearest neighbours (`neighbourhood.rs`), then
//! starts at the hint's leaf and climbs (`KdIndex::nearest_within`).
//! Distances are squared Euclidean in `f32`.

/// Most points in a leaf. With leaves scanned four points at a time, 64 registers pairs faster
/// in wasm than 32 or 16 (`BENCHMARK.md`, "The leaf scan, four distances at a time").
pub const LEAF: usize = 64;

mod chunk;
pub mod neighbourhood;

use chunk::Chunk;
use neighbourhood::Neighbourhood;
use std::sync::OnceLock;

/// Traversal stack size: the tree depth is at most `log2(u32::MAX) + 1 < 40`.
const STACK: usize = 48;

#[derive(Clone, Copy, Debug)]
struct Node {
    /// Split axis 0..3, or [`IS_LEAF`].
    dim: u32,
    /// Points with coordinate `<= split` are on the left, `>= split` on the right.
    split: f32,
    /// Inner node: left child index. Leaf: its first position (a multiple of four).
    a: u32,
    /// Inner node: right child index. Leaf: one past its last point's position.
    b: u32,
}

const IS_LEAF: u32 = 3;

/// A subtree still to visit, with the query's per-axis offsets to its cell (`off`, 0 where the
/// query is inside the cell's slab) and their squared sum `rd`, a lower bound of the squared
/// distance to any point in it (Arya & Mount's incremental distance).
#[derive(Clone, Copy)]
struct Pending {
    node: u32,
    rd: f32,
    off: [f32; 3],
}

impl Pending {
    const ROOT: Pending = Pending { node: 0, rd: 0.0, off: [0.0; 3] };
}

/// The two least of the squared distances and bounds a search recorded
/// ([`KdIndex::nearest_within_and_floor`]): every indexed point is at least the least away, and
/// every point but the one found at least the second.
#[derive(Clone, Copy)]
struct Floors {
    least: f32,
    second: f32,
    /// What the leaves' scans recorded, per lane of their chunks.
    lanes: chunk::LaneFloors,
}

impl Floors {
    /// Nothing recorded yet (and all that the searches without `FLOOR` record).
    const NONE: Floors = Floors { least: f32::INFINITY, second: f32::INFINITY, lanes: chunk::LaneFloors::NONE };

    /// Records the distance or bound `v` (only with `FLOOR`).
    #[inline(always)]
    fn record<const FLOOR: bool>(&mut self, v: f32) {
        if FLOOR {
            // selects, not branches: whether a scanned distance is among the two least is
            // unpredictable (natively the branches cost about a sixth of an any-pose pair's time)
            let below_least = v < self.least;
            let second = if v < self.second { v } else { self.second };
            self.second = if below_least { self.least } else { second };
            self.least = if below_least { v } else { self.least };
        }
    }

    /// The two least of everything recorded, the lanes' included.
    fn merged(mut self) -> Floors {
        let lanes = self.lanes;
        for l in 0..4 {
            self.record::<true>(lanes.least[l]);
            self.record::<true>(lanes.second[l]);
        }
        self
    }
}

/// The traversal stack of one query, not initialised: zeroing its `STACK` entries cost more than
/// a whole bounded ICP query's descent (a measurable share of ICP time).
struct Stack {
    items: [std::mem::MaybeUninit<Pending>; STACK],
    len: usize,
}

impl Stack {
    /// A stack holding the root.
    #[inline(always)]
    fn root() -> Self {
        let mut s = Stack { items: [const { std::mem::MaybeUninit::uninit() }; STACK], len: 0 };
        s.push(Pending::ROOT);
        s
    }

    #[inline(always)]
    fn push(&mut self, p: Pending) {
        // the tree depth bounds the length below STACK (see STACK); indexing keeps it checked
        self.items[self.len].write(p);
        self.len += 1;
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<Pending> {
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        // SAFETY: entries below `len` were written by `push` and `Pending` is `Copy`.
        Some(unsafe { self.items[self.len].assume_init() })
    }
}

/// A static k-d tree; the item of a point is its index in the slice the index was built from.
#[derive(Clone, Debug, Default)]
pub struct KdIndex {
    /// The points by position, four to a chunk: each leaf is a contiguous run of positions from
    /// a multiple of four, the rest of its last chunk padding (NaN, never found).
    chunks: Vec<Chunk>,
    /// Number of indexed points.
    count: usize,
    /// `ids[i]`: original index of the point at position `i` (`u32::MAX` for padding).
    ids: Vec<u32>,
    /// `pos[j]`: position of original point `j` (`u32::MAX` if not indexed).
    pos: Vec<u32>,
    nodes: Vec<Node>,
    /// `parent[n]`: the parent of node `n` (the root's is `u32::MAX`).
    parent: Vec<u32>,
    /// `cell[n]`: the region node `n` splits, `[lo, hi]` per axis (infinite at the root): every
    /// indexed point outside the subtree lies outside it or on its boundary.
    cell: Vec<[[f32; 3]; 2]>,
    /// `leaf_of[i]`: the leaf holding position `i`.
    leaf_of: Vec<u32>,
    /// `bbox[n]`: the bounding box `[lo, hi]` of node `n`'s points (tighter than its cell).
    bbox: Vec<[[f32; 3]; 2]>,
    /// Per position, the neighbourhood of the point there, found when it is first a hint
    /// (`neighbourhood.rs`); the table is allocated at the first hinted search.
    neighbourhoods: OnceLock<Vec<OnceLock<Neighbourhood>>>,
}

impl KdIndex {
    /// Builds the tree (O(n log n)). Points with a NaN or infinite coordinate are not indexed
    /// (never returned); an empty slice gives an index that answers every query with nothing.
    ///
    /// # Panics
    /// If there are `u32::MAX` points or more.
    pub fn new(points: &[[f32; 3]]) -> Self {
        assert!(points.len() < u32::MAX as usize, "KdIndex holds fewer than u32::MAX points");
        let mut order: Vec<u32> =
            (0..points.len() as u32).filter(|&i| points[i as usize].iter().all(|v| v.is_finite())).collect();
        let mut nodes = Vec::with_capacity(4 * order.len() / LEAF + 1);
        let mut bbox = Vec::with_capacity(nodes.capacity());
        if !order.is_empty() {
            build(points, &mut order, 0, &mut nodes, &mut bbox);
        }
        // positions: each leaf's run (in `order`'s order) from the next multiple of four
        let slots: usize =
            nodes.iter().filter(|n| n.dim == IS_LEAF).map(|n| (n.b - n.a).next_multiple_of(4) as usize).sum();
        assert!(slots < u32::MAX as usize, "KdIndex holds fewer than u32::MAX points");
        let mut chunks = vec![Chunk::PADDING; slots / 4];
        let mut ids = vec![u32::MAX; slots];
        let mut leaf_of = vec![0u32; slots];
        let mut pos = vec![u32::MAX; points.len()];
        let mut parent = vec![u32::MAX; nodes.len()];
        let mut cell = vec![[[f32::NEG_INFINITY; 3], [f32::INFINITY; 3]]; nodes.len()];
        let mut next = 0u32;
        // children come after their parent in `nodes` (pre-order), and leaves come in the order
        // of their runs in `order`
        for (i, n) in nodes.iter_mut().enumerate() {
            if n.dim == IS_LEAF {
                let run = &order[n.a as usize..n.b as usize];
                (n.a, n.b) = (next, next + run.len() as u32);
                for (p, &j) in (n.a..).zip(run) {
                    chunks[p as usize / 4].set(p as usize % 4, &points[j as usize]);
                    ids[p as usize] = j;
                    pos[j as usize] = p;
                }
                leaf_of[n.a as usize..n.b as usize].fill(i as u32);
                next = n.b.next_multiple_of(4);
                continue;
            }
            let d = n.dim as usize;
            let [lo, hi] = cell[i];
            parent[n.a as usize] = i as u32;
            parent[n.b as usize] = i as u32;
            let mut left_hi = hi;
            left_hi[d] = n.split;
            let mut right_lo = lo;
            right_lo[d] = n.split;
            cell[n.a as usize] = [lo, left_hi];
            cell[n.b as usize] = [right_lo, hi];
        }
        Self {
            chunks,
            count: order.len(),
            ids,
            pos,
            nodes,
            parent,
            cell,
            leaf_of,
            bbox,
            neighbourhoods: OnceLock::new(),
        }
    }

    /// Number of indexed (finite) points.
    pub fn len(&self) -> usize {
        self.count
    }

    /// True when the index holds no points.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// The chunks of leaf `n` (its first position is a multiple of four).
    #[inline(always)]
    fn leaf_chunks(&self, n: &Node) -> &[Chunk] {
        &self.chunks[n.a as usize / 4..(n.b as usize).div_ceil(4)]
    }

    /// Calls `f` with the position and squared distance to `q` of each slot of leaf `n`, in
    /// order; a padding slot's distance is NaN (below and within no bound).
    #[inline(always)]
    fn each_in_leaf(&self, n: &Node, q: &[f32; 3], mut f: impl FnMut(usize, f32)) {
        for (c, p) in self.leaf_chunks(n).iter().zip((n.a as usize..).step_by(4)) {
            for (i, d2) in (p..p + 4).zip(chunk::distances(c, q)) {
                f(i, d2);
            }
        }
    }

    /// The point at position `p`.
    #[inline(always)]
    fn point(&self, p: u32) -> [f32; 3] {
        self.chunks[p as usize / 4].get(p as usize % 4)
    }

    /// The nearest indexed point to `q`: `(index, squared distance)`, or `None` when the index
    /// is empty (or `q` has a NaN coordinate).
    #[inline]
    pub fn nearest(&self, q: &[f32; 3]) -> Option<(usize, f32)> {
        self.nearest_within(q, f32::INFINITY, None)
    }

    /// The nearest indexed point to `q` whose squared distance is **strictly below** `max_d2`,
    /// or `None`. `hint` is the index of a point believed to be close (e.g. the previous ICP
    /// iteration's partner); it only speeds the search up, never changes which distance is
    /// found (among points at exactly equal distance, which one is returned may depend on it).
    ///
    /// With a hint the search first looks among the hint's own nearest neighbours, which often
    /// show that one of them (or the hint) is the nearest point of all (`neighbourhood.rs`);
    /// otherwise it starts at the hint's leaf and climbs: at each node, once the ball
    /// of the best distance so far around `q` lies inside the node's cell, nothing outside can be
    /// nearer; else the parent's other child is searched top-down and the climb goes on. An ICP
    /// iteration's partner is usually the previous one or a neighbour, so most queries end in
    /// the hint's leaf or one level up, without descending from the root.
    #[inline]
    pub fn nearest_within(&self, q: &[f32; 3], max_d2: f32, hint: Option<usize>) -> Option<(usize, f32)> {
        let mut none = Floors::NONE;
        self.search::<false>(q, max_d2, hint, &mut none)
    }

    /// [`KdIndex::nearest_within`], and a *floor*: a lower bound of the squared distance from `q`
    /// to every indexed point other than the one found (to every point when none is found; then
    /// it is at least `max_d2`). It is the least of the bounds by which the search left subtrees
    /// out and of the distances it scanned, so for a query far from every point but the one
    /// found it is near the true distance of the second nearest. Computed in `f32`, it may
    /// exceed the true bound by a few units in the last place (a relative 1e-5 is ample).
    /// Without points or with a NaN coordinate in `q`: `(None, 0.0)`.
    ///
    /// ICP uses it to skip searches ([`crate::icp::Partners`]): a query that has moved by `m`
    /// since a search gave it the floor `f` is still at least `sqrt(f) - m` from every point but
    /// the one found; when that one is nearer, it is still the nearest.
    #[inline]
    pub fn nearest_within_and_floor(
        &self,
        q: &[f32; 3],
        max_d2: f32,
        hint: Option<usize>,
    ) -> (Option<(usize, f32)>, f32) {
        if self.nodes.is_empty() || q.iter().any(|v| v.is_nan()) {
            return (None, 0.0);
        }
        let mut floors = Floors::NONE;
        let found = self.search::<true>(q, max_d2, hint, &mut floors);
        let floors = floors.merged();
        // the point found is the least distance recorded (every bound that left a subtree out
        // was at least the best distance then); the others are at least the second
        match found {
            Some(f) => (Some(f), floors.second),
            None => (None, floors.least.max(max_d2)),
        }
    }

    /// The bounded nearest search of [`KdIndex::nearest_within`]; with `FLOOR`, every distance
    /// it scans and every bound by which it leaves out a subtree, or (climbing from a hint) all
    /// outside a cell, is recorded in `floors`.
    #[inline(always)]
    fn search<const FLOOR: bool>(
        &self,
        q: &[f32; 3],
        max_d2: f32,
        hint: Option<usize>,
        floors: &mut Floors,
    ) -> Option<(usize, f32)> {
        if self.nodes.is_empty() || q.iter().any(|v| v.is_nan()) {
            return None;
        }
        // best = (position in `pts` or u32::MAX, squared distance bound)
        let mut best = (u32::MAX, max_d2);
        let start = hint.and_then(|h| self.pos.get(h)).copied().filter(|&p| p != u32::MAX);
        match start {
            // most hinted searches end among the hint's own neighbours
            Some(p) => match self.nearest_from_neighbourhood::<FLOOR>(p, q, max_d2, floors) {
                Some(found) => best = found,
                None => self.climb_from::<FLOOR>(p, q, &mut best, floors),
            },
            None => self.nearest_from::<FLOOR>(Pending::ROOT, q, &mut best, floors),
        }
        (best.0 != u32::MAX).then(|| (self.ids[best.0 as usize] as usize, best.1))
    }

    /// The hinted search from the hint at position `p`: scans the hint's leaf, then climbs while
    /// the ball of the best distance so far around `q` crosses the cell of the node reached,
    /// searching each parent's other child top-down ([`KdIndex::nearest_within`]).
    #[inline(always)]
    fn climb_from<const FLOOR: bool>(&self, p: u32, q: &[f32; 3], best: &mut (u32, f32), floors: &mut Floors) {
        // (not recorded: the leaf's scan records it)
        let d2 = dist2(&self.point(p), q);
        if d2 < best.1 {
            *best = (p, d2);
        }
        let mut node = self.leaf_of[p as usize];
        self.scan_leaf::<FLOOR>(node, q, best, floors);
        loop {
            if let Some(outside) = self.ball_inside(node, q, best.1) {
                floors.record::<FLOOR>(outside);
                break;
            }
            let up = self.parent[node as usize];
            if up == u32::MAX {
                break;
            }
            let n = self.nodes[up as usize];
            let other = if n.a == node { n.b } else { n.a };
            let off = self.offsets(other, q);
            let rd = off[0] * off[0] + off[1] * off[1] + off[2] * off[2];
            if rd < best.1 {
                self.nearest_from::<FLOOR>(Pending { node: other, rd, off }, q, best, floors);
            } else {
                floors.record::<FLOOR>(rd);
            }
            node = up;
        }
    }

    /// Scans leaf `node` for points nearer than `best` (strictly); with `FLOOR`, records each
    /// distance in `floors`.
    #[inline(always)]
    fn scan_leaf<const FLOOR: bool>(&self, node: u32, q: &[f32; 3], best: &mut (u32, f32), floors: &mut Floors) {
        let n = self.nodes[node as usize];
        let (least, at) = chunk::nearest::<FLOOR>(self.leaf_chunks(&n), n.a, q, best.1, &mut floors.lanes);
        for l in 0..4 {
            if least[l] < best.1 || (least[l] == best.1 && at[l] < best.0) {
                *best = (at[l], least[l]);
            }
        }
    }

    /// When every point outside node `node`'s subtree is at squared distance `>= d2` from `q`
    /// (`q` is inside the node's cell, at least `sqrt(d2)` from each of its faces), the squared
    /// distance to its nearest face, a lower bound of theirs; else `None`.
    #[inline(always)]
    fn ball_inside(&self, node: u32, q: &[f32; 3], d2: f32) -> Option<f32> {
        let [lo, hi] = self.cell[node as usize];
        let mut nearest = f32::INFINITY;
        for a in 0..3 {
            let (l, h) = (q[a] - lo[a], hi[a] - q[a]);
            if !(l >= 0.0 && h >= 0.0 && l * l >= d2 && h * h >= d2) {
                return None;
            }
            let face = if l < h { l * l } else { h * h };
            nearest = if face < nearest { face } else { nearest };
        }
        Some(nearest)
    }

    /// Squared distance from `q` to node `node`'s bounding box (a lower bound of its points').
    #[inline(always)]
    fn box_d2(&self, node: u32, q: &[f32; 3]) -> f32 {
        let [lo, hi] = self.bbox[node as usize];
        let mut d2 = 0.0;
        for a in 0..3 {
            // comparisons, not f32::max: wasm's f32.max differs from Rust's on NaN, so `max`
            // compiles to a call there
            let below = lo[a] - q[a];
            let above = q[a] - hi[a];
            let e = if below > 0.0 {
                below
            } else if above > 0.0 {
                above
            } else {
                0.0
            };
            d2 += e * e;
        }
        d2
    }

    /// Per-axis offsets from `q` to node `node`'s cell (0 inside its slab).
    #[inline(always)]
    fn offsets(&self, node: u32, q: &[f32; 3]) -> [f32; 3] {
        let [lo, hi] = self.cell[node as usize];
        std::array::from_fn(|a| {
            if q[a] < lo[a] {
                q[a] - lo[a]
            } else if q[a] > hi[a] {
                q[a] - hi[a]
            } else {
                0.0
            }
        })
    }

    /// The top-down bounded nearest search of the subtree `from`, updating `best`; with `FLOOR`,
    /// records in `floors` every bound by which it leaves a subtree out and every distance it
    /// scans.
    #[inline(always)]
    fn nearest_from<const FLOOR: bool>(&self, from: Pending, q: &[f32; 3], best: &mut (u32, f32), floors: &mut Floors) {
        let mut stack = Stack::root();
        stack.items[0].write(from);
        while let Some(Pending { node, rd, off }) = stack.pop() {
            if rd >= best.1 {
                floors.record::<FLOOR>(rd);
                continue;
            }
            let mut ni = node;
            loop {
                // the points' own box: prunes queries beyond the cloud's edge, which the
                // (unbounded) border cells do not
                let box_d2 = self.box_d2(ni, q);
                if box_d2 >= best.1 {
                    floors.record::<FLOOR>(box_d2);
                    break;
                }
                let n = self.nodes[ni as usize];
                if n.dim == IS_LEAF {
                    self.scan_leaf::<FLOOR>(ni, q, best, floors);
                    break;
                }
                let d = n.dim as usize;
                let diff = q[d] - n.split;
                let (near, far) = if diff < 0.0 { (n.a, n.b) } else { (n.b, n.a) };
                let far_rd = rd - off[d] * off[d] + diff * diff;
                if far_rd < best.1 {
                    let mut far_off = off;
                    far_off[d] = diff;
                    stack.push(Pending { node: far, rd: far_rd, off: far_off });
                } else {
                    floors.record::<FLOOR>(far_rd);
                }
                ni = near;
            }
        }
    }

    /// Calls `leaf` on every leaf that may hold a point within the squared distance `bound` of
    /// `q` (`<= bound` with `INCLUSIVE`, else `< bound`), nearest side first; `leaf` returns the
    /// bound from then on (a k-nearest search's shrinks as it fills). The index must not be empty.
    #[inline(always)]
    fn leaves_within<const INCLUSIVE: bool>(&self, q: &[f32; 3], mut bound: f32, mut leaf: impl FnMut(&Node) -> f32) {
        let within = |d2: f32, bound: f32| if INCLUSIVE { d2 <= bound } else { d2 < bound };
        let mut stack = Stack::root();
        while let Some(Pending { node, rd, off }) = stack.pop() {
            if !within(rd, bound) {
                continue;
            }
            let mut ni = node;
            loop {
                let n = self.nodes[ni as usize];
                if n.dim == IS_LEAF {
                    bound = leaf(&n);
                    break;
                }
                let d = n.dim as usize;
                let diff = q[d] - n.split;
                let (near, far) = if diff < 0.0 { (n.a, n.b) } else { (n.b, n.a) };
                let far_rd = rd - off[d] * off[d] + diff * diff;
                if within(far_rd, bound) {
                    let mut far_off = off;
                    far_off[d] = diff;
                    stack.push(Pending { node: far, rd: far_rd, off: far_off });
                }
                ni = near;
            }
        }
    }

    /// The `k` nearest indexed points to `q` (fewer if the index is smaller), nearest first,
    /// written into `out` (cleared first) as `(index, squared distance)`. Allocation-free once
    /// `out` has capacity `k`.
    pub fn knn_into(&self, q: &[f32; 3], k: usize, out: &mut Vec<(usize, f32)>) {
        self.knn_positions(q, k, out);
        for e in out.iter_mut() {
            e.0 = self.ids[e.0] as usize;
        }
    }

    /// [`KdIndex::knn_into`] with positions in the index instead of the points' indices.
    fn knn_positions(&self, q: &[f32; 3], k: usize, out: &mut Vec<(usize, f32)>) {
        out.clear();
        let k = k.min(self.count);
        if k == 0 {
            return;
        }
        // `out` holds (position, d2), sorted ascending by d2 (equals in the order found), during
        // the search; an insertion shifts the farther entries by hand (no `memmove` call)
        let mut worst = f32::INFINITY;
        self.leaves_within::<false>(q, worst, |n| {
            for (c, p) in self.leaf_chunks(n).iter().zip((n.a as usize..).step_by(4)) {
                let d2 = chunk::distances(c, q);
                // one test per chunk: most chunks of a visited leaf hold no nearer point
                if !d2.iter().any(|&d| d < worst) {
                    continue;
                }
                for (l, &d) in d2.iter().enumerate() {
                    if d < worst {
                        if out.len() < k {
                            out.push((0, 0.0));
                        }
                        let mut at = out.len() - 1;
                        while at > 0 && out[at - 1].1 > d {
                            out[at] = out[at - 1];
                            at -= 1;
                        }
                        out[at] = (p + l, d);
                        if out.len() == k {
                            worst = out[k - 1].1;
                        }
                    }
                }
            }
            worst
        });
    }

    /// The indexed points within squared distance `max_d2` of `q` (`<=`), at most `max` of them
    /// (the nearest `max` when there are more), written into `out` (cleared first) as
    /// `(index, squared distance)`, nearest first. Allocation-free once `out` has the capacity
    /// of the neighbourhood; cheaper than [`KdIndex::knn_into`] when `max` is large.
    pub fn within_into(&self, q: &[f32; 3], max_d2: f32, max: usize, out: &mut Vec<(usize, f32)>) {
        out.clear();
        if self.nodes.is_empty() || max == 0 || max_d2.is_nan() {
            return;
        }
        self.leaves_within::<true>(q, max_d2, |n| {
            self.each_in_leaf(n, q, |i, d2| {
                if d2 <= max_d2 {
                    out.push((i, d2));
                }
            });
            max_d2
        });
        // nearest first, ties by index: the same neighbourhood whatever the traversal order
        let by = |a: &(usize, f32), b: &(usize, f32)| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0));
        if out.len() > max {
            out.select_nth_unstable_by(max - 1, by);
            out.truncate(max);
        }
        out.sort_unstable_by(by);
        for e in out.iter_mut() {
            e.0 = self.ids[e.0] as usize;
        }
    }
}

#[inline(always)]
pub(crate) fn dist2(p: &[f32; 3], q: &[f32; 3]) -> f32 {
    let dx = p[0] - q[0];
    let dy = p[1] - q[1];
    let dz = p[2] - q[2];
    dx * dx + dy * dy + dz * dz
}

/// Builds the subtree over `idx` (whose points will occupy positions `offset..` of the
/// reordered array) and returns its node index.
fn build(
    points: &[[f32; 3]],
    idx: &mut [u32],
    offset: u32,
    nodes: &mut Vec<Node>,
    bbox: &mut Vec<[[f32; 3]; 2]>,
) -> u32 {
    let me = nodes.len() as u32;
    let leaf = Node { dim: IS_LEAF, split: 0.0, a: offset, b: offset + idx.len() as u32 };
    nodes.push(leaf);
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for &i in idx.iter() {
        crate::cloud::grow_box(&mut lo, &mut hi, &points[i as usize]);
    }
    bbox.push([lo, hi]);
    if idx.len() <= LEAF {
        return me;
    }
    let mut dim = 0;
    for a in 1..3 {
        if hi[a] - lo[a] > hi[dim] - lo[dim] {
            dim = a;
        }
    }
    if hi[dim] <= lo[dim] {
        // All points coincide (or are NaN): one big leaf.
        return me;
    }
    let mid = idx.len() / 2;
    idx.select_nth_unstable_by(mid, |&a, &b| points[a as usize][dim].total_cmp(&points[b as usize][dim]));
    let split = points[idx[mid] as usize][dim];
    let (l, r) = idx.split_at_mut(mid);
    let left = build(points, l, offset, nodes, bbox);
    let right = build(points, r, offset + mid as u32, nodes, bbox);
    nodes[me as usize] = Node { dim: dim as u32, split, a: left, b: right };
    me
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cloud(n: usize) -> Vec<[f32; 3]> {
        (0..n)
            .map(|i| {
                let f = i as f32;
                [(f * 0.37).sin() * 3.0, (f * 0.11).cos() * 2.0, ((f * 0.05).sin() * 4.0).round() * 0.25]
            })
            .collect()
    }

    fn brute(pts: &[[f32; 3]], q: &[f32; 3]) -> Vec<f32> {
        let mut d: Vec<f32> = pts.iter().filter(|p| p.iter().all(|v| v.is_finite())).map(|p| dist2(p, q)).collect();
        d.sort_by(f32::total_cmp);
        d
    }

    #[test]
    fn queries_match_brute_force() {
        let mut pts = cloud(2000);
        pts.extend([[0.5, 0.5, 0.5]; 40]); // duplicates
        pts.push([f32::NAN, 0.0, 0.0]);
        pts.push([f32::INFINITY, 0.0, 0.0]);
        let idx = KdIndex::new(&pts);
        assert_eq!(idx.len(), 2040);
        let mut out = Vec::new();
        for (k, q) in [[0.1f32, 0.2, 0.3], [3.0, -2.0, 1.0], [-10.0, 0.0, 0.0], [0.5, 0.5, 0.5], [0.0, 0.0, 0.25]]
            .iter()
            .chain(pts[..300].iter().step_by(7))
            .enumerate()
        {
            let all = brute(&pts, q);
            let (i, d) = idx.nearest(q).unwrap();
            assert_eq!(d, all[0]);
            assert_eq!(dist2(&pts[i], q), d);
            // bounded: strictly below the bound, else None
            assert_eq!(idx.nearest_within(q, all[0], None), None);
            assert_eq!(idx.nearest_within(q, all[0] * 1.5 + 1e-6, None).map(|r| r.1), Some(all[0]));
            // a hint never changes the distance found
            for h in [0, k * 13 % 2000, i, 2040, 5000] {
                assert_eq!(idx.nearest_within(q, f32::INFINITY, Some(h)).unwrap().1, all[0]);
            }
            idx.knn_into(q, 15, &mut out);
            let got: Vec<f32> = out
                .iter()
                .map(|&(i, d)| {
                    assert_eq!(dist2(&pts[i], q), d);
                    d
                })
                .collect();
            assert_eq!(got, all[..15].to_vec());
            let mut ids: Vec<usize> = out.iter().map(|e| e.0).collect();
            ids.sort();
            ids.dedup();
            assert_eq!(ids.len(), 15);
        }
        idx.knn_into(&[0.0; 3], 5000, &mut out);
        assert_eq!(out.len(), 2040);
        // within a radius: every point within it, nearest first, ties by position
        for q in [[0.1f32, 0.2, 0.3], [0.5, 0.5, 0.5], [3.0, -2.0, 1.0]] {
            let all = brute(&pts, &q);
            for r2 in [0.0, all[3], all[40], all[200] * 1.001] {
                idx.within_into(&q, r2, usize::MAX, &mut out);
                let want: Vec<f32> = all.iter().copied().filter(|&d| d <= r2).collect();
                assert_eq!(out.iter().map(|e| e.1).collect::<Vec<_>>(), want);
                assert!(out.iter().all(|&(i, d)| dist2(&pts[i], &q) == d));
                idx.within_into(&q, r2, 5, &mut out);
                assert_eq!(out.iter().map(|e| e.1).collect::<Vec<_>>(), want[..want.len().min(5)].to_vec());
            }
        }
        assert!(idx.nearest(&[f32::NAN, 0.0, 0.0]).is_none());
    }

    #[test]
    fn hinted_search_climbs_to_the_exact_nearest() {
        // ICP-like queries: points moved a little, hinted with a point near the old position
        let pts = cloud(3000);
        let idx = KdIndex::new(&pts);
        for (k, p) in pts.iter().enumerate().step_by(3) {
            let f = k as f32;
            let q = [p[0] + 0.05 * (f * 0.7).sin(), p[1] + 0.05 * (f * 1.3).cos(), p[2] - 0.03 * (f * 0.3).sin()];
            let all = brute(&pts, &q);
            for bound in [f32::INFINITY, all[0] * 4.0 + 1e-4, all[0], all[0] * 0.5] {
                let want = (all[0] < bound).then_some(all[0]);
                for h in [k, (k + 1) % 3000, (k * 7919) % 3000] {
                    let got = idx.nearest_within(&q, bound, Some(h));
                    assert_eq!(got.map(|r| r.1), want, "query {k}, hint {h}, bound {bound}");
                    if let Some((i, d)) = got {
                        assert_eq!(dist2(&pts[i], &q), d);
                    }
                }
            }
        }
    }

    #[test]
    fn searches_give_floors_below_every_other_point() {
        let mut pts = cloud(2500);
        pts.extend([[0.5, 0.5, 0.5]; 30]);
        let idx = KdIndex::new(&pts);
        let (mut tight, mut count) = (0, 0);
        for k in 0..400 {
            let f = k as f32;
            // queries near the points, beyond their box, and far away; hinted or not
            let q = [(f * 0.71).sin() * 4.0, (f * 0.13).cos() * 3.0 + (k % 3) as f32, (f * 0.29).sin() * 2.5];
            let all = brute(&pts, &q);
            let (nearest, second) = (all[0], all[1]);
            for hint in [None, Some(k), Some(k * 7 % 2530)] {
                // nothing within the bound: the floor bounds every point
                for bound in [nearest * 0.99, nearest * 0.5, 1e-6] {
                    let (found, floor) = idx.nearest_within_and_floor(&q, bound, hint);
                    assert_eq!(found, None);
                    assert!(
                        floor >= bound && floor <= nearest * (1.0 + 1e-5),
                        "{q:?}: floor {floor}, nearest {nearest}"
                    );
                }
                // found: the floor bounds every other point
                for bound in [f32::INFINITY, nearest * 1.01 + 1e-6, second * 2.0 + 1e-6] {
                    let (found, floor) = idx.nearest_within_and_floor(&q, bound, hint);
                    assert_eq!(found.map(|r| r.1), Some(nearest));
                    assert!(
                        floor >= nearest && floor <= second * (1.0 + 1e-5),
                        "{q:?}: floor {floor}, second {second}"
                    );
                    tight += (floor >= 0.5 * second) as usize;
                    count += 1;
                }
            }
        }
        // a floor is mostly close to the true distance, not merely the bound
        assert!(tight * 10 > count * 8, "{tight} of {count} floors within half the second distance");
        assert_eq!(KdIndex::new(&[]).nearest_within_and_floor(&[0.0; 3], 1.0, None), (None, 0.0));
        assert_eq!(idx.nearest_within_and_floor(&[f32::NAN, 0.0, 0.0], 1.0, None), (None, 0.0));
    }

    #[test]
    fn leaves_of_every_length_modulo_four() {
        // leaves are runs from a multiple of four: clouds whose leaves end on every lane, and
        // one point
        for n in [1, 2, 3, 5, 17, 18, 19, 33, 34, 35, 61, 62, 63, 100, 129] {
            let pts = cloud(n);
            let idx = KdIndex::new(&pts);
            assert_eq!(idx.len(), n);
            let mut out = Vec::new();
            for (k, q) in pts.iter().enumerate() {
                let q = [q[0] + 0.01, q[1] - 0.02, q[2] + 0.015];
                let all = brute(&pts, &q);
                let (i, d) = idx.nearest(&q).unwrap();
                assert_eq!((d, dist2(&pts[i], &q)), (all[0], all[0]), "{n} points");
                assert_eq!(idx.nearest_within(&q, f32::INFINITY, Some(k)).unwrap().1, all[0]);
                let (found, floor) = idx.nearest_within_and_floor(&q, f32::INFINITY, Some((k * 7) % n));
                assert_eq!(found.map(|f| f.1), Some(all[0]));
                let second = all.get(1).copied().unwrap_or(f32::INFINITY);
                assert!(floor >= all[0] && floor <= second * (1.0 + 1e-5), "{n} points: floor {floor}");
                idx.knn_into(&q, n, &mut out);
                assert_eq!(out.iter().map(|e| e.1).collect::<Vec<_>>(), all);
                let mut ids: Vec<usize> = out.iter().map(|e| e.0).collect();
                ids.sort();
                assert_eq!(ids, (0..n).collect::<Vec<_>>());
            }
        }
    }

    #[test]
    fn empty_and_coincident() {
        let idx = KdIndex::new(&[]);
        assert!(idx.is_empty());
        assert!(idx.nearest(&[0.0; 3]).is_none());
        let mut out = vec![(1, 0.0)];
        idx.knn_into(&[0.0; 3], 3, &mut out);
        assert!(out.is_empty());
        let same = KdIndex::new(&[[1.0, 1.0, 1.0]; 100]);
        assert_eq!(same.nearest(&[0.0; 3]).unwrap().1, 3.0);
        same.knn_into(&[0.0; 3], 7, &mut out);
        assert_eq!(out.len(), 7);
    }
}
