//! The tape: a linear record of operations on row-major `f32` tensors, with reverse-mode
//! gradients.
//!
//! Every value is a node `[rows, cols]` (row-major `f32`). Leaves are constants or parameters;
//! every other node is made by an op (see [`super::ops`]) that knows how to push its output's
//! gradient back to its inputs. Nodes are created in topological order, so the backward pass is a
//! single reverse sweep. A node "needs a gradient" when it is a parameter or depends on one; ops
//! skip the work for inputs that do not.
//!
//! Buffers are recycled: [`Tape::reset`] keeps every allocation in a pool that later nodes,
//! gradients and op scratch draw from, so a tape reused across training steps stops allocating
//! after the first step.

use std::fmt;

/// Handle to a node of a [`Tape`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Id(pub(crate) usize);

impl Id {
    /// Position of the node on its tape.
    pub fn index(self) -> usize {
        self.0
    }
}

/// The backward half of an op: pushes the gradient of the op's output to its inputs.
pub trait Op: Send {
    /// Short name, for debugging and profiles.
    fn name(&self) -> &'static str;
    /// Accumulates the input gradients given the gradient `g` of the output node `out`.
    fn backward(&self, ctx: &mut Backward<'_>, out: Id, g: &[f32]);
    /// Returns owned scratch buffers (saved activations) to the pool when the tape is reset.
    fn recycle(self: Box<Self>, _pool: &mut Pool) {}
}

/// A recorded node.
pub struct Node {
    pub(crate) value: Vec<f32>,
    pub(crate) rows: usize,
    pub(crate) cols: usize,
    pub(crate) op: Option<Box<dyn Op>>,
    pub(crate) needs_grad: bool,
}

impl fmt::Debug for Node {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Node")
            .field("rows", &self.rows)
            .field("cols", &self.cols)
            .field("op", &self.op.as_ref().map(|o| o.name()))
            .field("needs_grad", &self.needs_grad)
            .finish()
    }
}

/// A pool of reusable `f32` buffers.
#[derive(Default, Debug)]
pub struct Pool {
    /// Free buffers by length (each has `len == capacity`).
    free: std::collections::BTreeMap<usize, Vec<Vec<f32>>>,
}

impl Pool {
    /// A zero-filled buffer of `len` elements (reusing the smallest free buffer that fits).
    pub fn zeros(&mut self, len: usize) -> Vec<f32> {
        let mut v = self.uninit(len);
        v.fill(0.0);
        v
    }

    /// A buffer of `len` elements whose contents are unspecified (stale values of an earlier
    /// use, or zeros): for outputs the caller overwrites entirely.
    pub fn uninit(&mut self, len: usize) -> Vec<f32> {
        // Free buffers are kept with len == capacity (all initialised), so truncating is safe
        // and costs nothing. Best fit: the shortest free buffer that is long enough.
        let key = self.free.range(len..).next().map(|(&k, _)| k);
        match key {
            Some(k) => {
                let list = self.free.get_mut(&k).expect("key exists");
                let mut v = list.pop().expect("lists are never left empty");
                if list.is_empty() {
                    self.free.remove(&k);
                }
                v.truncate(len);
                v
            }
            None => vec![0.0; len],
        }
    }

    /// Gives a buffer back.
    pub fn give(&mut self, mut v: Vec<f32>) {
        if v.capacity() > 0 {
            let c = v.capacity();
            v.resize(c, 0.0);
            self.free.entry(c).or_default().push(v);
        }
    }
}

/// Time spent per op kind (when profiling is on).
#[derive(Clone, Debug, Default)]
pub struct Profile {
    /// `(op name, forward seconds, backward seconds, count)`, in first-seen order.
    pub ops: Vec<(&'static str, f64, f64, usize)>,
    mark: Option<std::time::Instant>,
}

impl Profile {
    fn entry(&mut self, name: &'static str) -> &mut (&'static str, f64, f64, usize) {
        let i = match self.ops.iter().position(|e| e.0 == name) {
            Some(i) => i,
            None => {
                self.ops.push((name, 0.0, 0.0, 0));
                self.ops.len() - 1
            }
        };
        &mut self.ops[i]
    }

    /// Attributes the time since the last mark to `name`'s forward.
    fn forward(&mut self, name: &'static str) {
        let now = std::time::Instant::now();
        if let Some(m) = self.mark {
            let e = self.entry(name);
            e.1 += (now - m).as_secs_f64();
            e.3 += 1;
        }
        self.mark = Some(now);
    }
}

/// The tape.
#[derive(Default)]
pub struct Tape {
    pub(crate) nodes: Vec<Node>,
    grads: Vec<Vec<f32>>,
    pub(crate) pool: Pool,
    profile: Option<Profile>,
    scalars64: Vec<(usize, f64)>,
}

impl fmt::Debug for Tape {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Tape").field("nodes", &self.nodes.len()).finish()
    }
}

/// What an op's backward sees: every node's value (read-only) and the gradient store.
pub struct Backward<'a> {
    nodes: &'a [Node],
    grads: &'a mut [Vec<f32>],
    pool: &'a mut Pool,
}

impl<'a> Backward<'a> {
    /// The forward value of a node.
    pub fn value(&self, id: Id) -> &'a [f32] {
        &self.nodes[id.0].value
    }

    /// `(rows, cols)` of a node.
    pub fn shape(&self, id: Id) -> (usize, usize) {
        let n = &self.nodes[id.0];
        (n.rows, n.cols)
    }

    /// Whether a gradient must be pushed to this node.
    pub fn needs(&self, id: Id) -> bool {
        self.nodes[id.0].needs_grad
    }

    /// The gradient accumulator of a node (zero-initialised on first use).
    pub fn grad(&mut self, id: Id) -> &mut [f32] {
        let len = self.nodes[id.0].value.len();
        let g = &mut self.grads[id.0];
        if g.len() != len {
            *g = self.pool.zeros(len);
        }
        g
    }

    /// Adds `delta` into the gradient of `id` (if it needs one).
    pub fn accumulate(&mut self, id: Id, delta: &[f32]) {
        if !self.needs(id) {
            return;
        }
        for (g, d) in self.grad(id).iter_mut().zip(delta) {
            *g += d;
        }
    }

    /// A zeroed scratch buffer; give it back with [`Backward::give`].
    pub fn scratch(&mut self, len: usize) -> Vec<f32> {
        self.pool.zeros(len)
    }

    /// Returns a scratch buffer to the pool.
    pub fn give(&mut self, v: Vec<f32>) {
        self.pool.give(v);
    }
}

impl Tape {
    /// An empty tape.
    pub fn new() -> Self {
        Self::default()
    }

    /// Clears all nodes and gradients, keeping their buffers for reuse.
    pub fn reset(&mut self) {
        for node in self.nodes.drain(..) {
            self.pool.give(node.value);
            if let Some(op) = node.op {
                op.recycle(&mut self.pool);
            }
        }
        for g in self.grads.drain(..) {
            self.pool.give(g);
        }
        self.scalars64.clear();
    }

    /// Records the unrounded value of a `1 x 1` node (ops that accumulate in `f64` call this).
    pub fn set_scalar64(&mut self, id: Id, v: f64) {
        self.scalars64.push((id.0, v));
    }

    /// The value of a `1 x 1` node in `f64`: the unrounded value if its op recorded one,
    /// else the `f32` value.
    pub fn scalar64(&self, id: Id) -> f64 {
        self.scalars64.iter().rev().find(|(i, _)| *i == id.0).map_or_else(|| self.scalar(id) as f64, |&(_, v)| v)
    }

    /// Turns on per-op timing (forward time is the time between consecutive node records,
    /// so it includes the caller's glue).
    pub fn enable_profile(&mut self) {
        self.profile = Some(Profile { mark: Some(std::time::Instant::now()), ..Profile::default() });
    }

    /// The timing so far (None unless [`Tape::enable_profile`] was called).
    pub fn profile(&self) -> Option<&Profile> {
        self.profile.as_ref()
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Whether the tape is empty.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// A constant leaf (no gradient).
    pub fn constant(&mut self, data: &[f32], rows: usize, cols: usize) -> Id {
        assert_eq!(data.len(), rows * cols, "constant: data length vs shape");
        let mut v = self.pool.uninit(data.len());
        v.copy_from_slice(data);
        self.leaf(v, rows, cols, false)
    }

    /// A parameter leaf (its gradient is kept after [`Tape::backward`]).
    pub fn param(&mut self, data: &[f32], rows: usize, cols: usize) -> Id {
        assert_eq!(data.len(), rows * cols, "param: data length vs shape");
        let mut v = self.pool.uninit(data.len());
        v.copy_from_slice(data);
        self.leaf(v, rows, cols, true)
    }

    /// A leaf from an owned buffer.
    pub fn leaf(&mut self, value: Vec<f32>, rows: usize, cols: usize, needs_grad: bool) -> Id {
        assert_eq!(value.len(), rows * cols, "leaf: data length vs shape");
        if let Some(p) = &mut self.profile {
            p.forward("leaf");
        }
        self.nodes.push(Node { value, rows, cols, op: None, needs_grad });
        Id(self.nodes.len() - 1)
    }

    /// Records an op's output. `needs_grad` is usually `inputs.any(needs)`; an op whose output
    /// needs no gradient is stored without its backward.
    pub fn push(&mut self, value: Vec<f32>, rows: usize, cols: usize, op: Box<dyn Op>, needs_grad: bool) -> Id {
        debug_assert_eq!(value.len(), rows * cols, "{}: output length vs shape", op.name());
        if let Some(p) = &mut self.profile {
            p.forward(op.name());
        }
        let op = if needs_grad {
            Some(op)
        } else {
            op.recycle(&mut self.pool);
            None
        };
        self.nodes.push(Node { value, rows, cols, op, needs_grad });
        Id(self.nodes.len() - 1)
    }

    /// The value of a node.
    pub fn value(&self, id: Id) -> &[f32] {
        &self.nodes[id.0].value
    }

    /// The scalar value of a `1 x 1` node.
    pub fn scalar(&self, id: Id) -> f32 {
        let v = self.value(id);
        assert_eq!(v.len(), 1, "scalar: node is not 1x1");
        v[0]
    }

    /// `(rows, cols)` of a node.
    pub fn shape(&self, id: Id) -> (usize, usize) {
        let n = &self.nodes[id.0];
        (n.rows, n.cols)
    }

    /// Whether the node depends on a parameter.
    pub fn needs_grad(&self, id: Id) -> bool {
        self.nodes[id.0].needs_grad
    }

    /// Whether any of `ids` needs a gradient.
    pub fn any_needs(&self, ids: &[Id]) -> bool {
        ids.iter().any(|&i| self.nodes[i.0].needs_grad)
    }

    /// A zeroed buffer from the pool (for op outputs and saved activations).
    pub fn zeros(&mut self, len: usize) -> Vec<f32> {
        self.pool.zeros(len)
    }

    /// A buffer from the pool with unspecified contents (the op overwrites all of it).
    pub fn uninit(&mut self, len: usize) -> Vec<f32> {
        self.pool.uninit(len)
    }

    /// Reverse sweep from a `1 x 1` node, seeded with `d loss = 1`. Gradients of leaves are kept
    /// (read them with [`Tape::grad`]); those of inner nodes are freed as soon as they are used.
    /// May be called once per forward.
    pub fn backward(&mut self, loss: Id) {
        self.backward_seeded(loss, &[1.0]);
    }

    /// Reverse sweep from any node with a given output gradient `seed` (same length as the node).
    pub fn backward_seeded(&mut self, out: Id, seed: &[f32]) {
        assert_eq!(seed.len(), self.nodes[out.0].value.len(), "backward: seed length");
        self.grads.resize_with(self.nodes.len(), Vec::new);
        let mut g0 = self.pool.uninit(seed.len());
        g0.copy_from_slice(seed);
        self.grads[out.0] = g0;
        for i in (0..=out.0).rev() {
            if self.grads[i].is_empty() || self.nodes[i].op.is_none() {
                continue;
            }
            let g = std::mem::take(&mut self.grads[i]);
            let start = self.profile.as_ref().map(|_| std::time::Instant::now());
            {
                let (nodes, grads, pool) = (&self.nodes, &mut self.grads, &mut self.pool);
                let op = nodes[i].op.as_ref().expect("checked");
                let mut ctx = Backward { nodes, grads, pool };
                op.backward(&mut ctx, Id(i), &g);
            }
            if let (Some(p), Some(s)) = (&mut self.profile, start) {
                let name = self.nodes[i].op.as_ref().map_or("leaf", |o| o.name());
                p.entry(name).2 += s.elapsed().as_secs_f64();
            }
            self.pool.give(g);
        }
    }

    /// The gradient of a node after [`Tape::backward`] (`None` if nothing reached it).
    pub fn grad(&self, id: Id) -> Option<&[f32]> {
        self.grads.get(id.0).filter(|g| !g.is_empty()).map(|g| g.as_slice())
    }
}
