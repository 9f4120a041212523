//! Fully connected layers.

use super::{activation::relu_inplace, matmul::gemm, matmul::matmul_bt, qlinear::QuantWeight, workspace::take};

/// `y = x W^T + b` with `W` stored `[out, in]` row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct Linear {
    /// Weight, `[out, in]` row-major.
    pub weight: Vec<f32>,
    /// Bias, `[out]` (absent for bias-free layers).
    pub bias: Option<Vec<f32>>,
    /// Input width.
    pub in_dim: usize,
    /// Output width.
    pub out_dim: usize,
    /// The weight as integers, when it was stored as int8: the layer is then computed in
    /// integers ([`QuantWeight`]; `weight` holds the same values as `f32`).
    pub quant: Option<QuantWeight>,
}

impl Linear {
    /// Applies the layer to `rows` row-major inputs of width `in_dim`; writes `[rows, out_dim]`.
    pub fn forward(&self, x: &[f32], rows: usize, y: &mut [f32]) {
        debug_assert_eq!(x.len(), rows * self.in_dim);
        debug_assert_eq!(y.len(), rows * self.out_dim);
        if self.quant.as_ref().is_some_and(|q| q.forward(x, rows, y, self.bias.as_deref(), false)) {
            return;
        }
        matmul_bt(x, &self.weight, y, rows, self.in_dim, self.out_dim);
        if let Some(b) = &self.bias {
            for row in y.chunks_exact_mut(self.out_dim) {
                for (v, bi) in row.iter_mut().zip(b) {
                    *v += bi;
                }
            }
        }
    }

    /// The transposed output: writes `y^T = W x^T + b` as `[out_dim, rows]` row-major (e.g. the
    /// keys of attention, so that each head's `K_h^T` is a contiguous block of rows).
    pub fn forward_transposed(&self, x: &[f32], rows: usize, yt: &mut [f32]) {
        debug_assert_eq!(x.len(), rows * self.in_dim);
        debug_assert_eq!(yt.len(), rows * self.out_dim);
        if self.quant.as_ref().is_some_and(|q| q.forward(x, rows, yt, self.bias.as_deref(), true)) {
            return;
        }
        let (i, r) = (self.in_dim as isize, rows as isize);
        gemm(self.out_dim, self.in_dim, rows, 1.0, &self.weight, i, 1, x, 1, i, 0.0, yt, r, 1);
        if let Some(b) = &self.bias {
            for (row, bi) in yt.chunks_exact_mut(rows.max(1)).zip(b) {
                for v in row.iter_mut() {
                    *v += bi;
                }
            }
        }
    }
}

/// A stack of [`Linear`] layers with ReLU after each one except, optionally, the last.
#[derive(Clone, Debug, PartialEq)]
pub struct Mlp {
    /// The layers, in order.
    pub layers: Vec<Linear>,
    /// Whether the last layer is followed by a ReLU too.
    pub relu_last: bool,
}

impl Mlp {
    /// Output width.
    pub fn out_dim(&self) -> usize {
        self.layers.last().map_or(0, |l| l.out_dim)
    }

    /// Applies the MLP to `[rows, in]`; writes `[rows, out_dim]` to `y`. `a`, `b` are scratch.
    pub fn forward(&self, x: &[f32], rows: usize, y: &mut [f32], a: &mut Vec<f32>, b: &mut Vec<f32>) {
        let n = self.layers.len();
        let first = &self.layers[0];
        if n == 1 {
            first.forward(x, rows, y);
            if self.relu_last {
                relu_inplace(y);
            }
            return;
        }
        let out = take(a, rows * first.out_dim);
        first.forward(x, rows, out);
        relu_inplace(out);
        let mut current_in_a = true;
        for (i, layer) in self.layers.iter().enumerate().skip(1) {
            let (src, dst) = if current_in_a { (&*a, &mut *b) } else { (&*b, &mut *a) };
            let src = &src[..rows * layer.in_dim];
            if i == n - 1 {
                layer.forward(src, rows, y);
                if self.relu_last {
                    relu_inplace(y);
                }
            } else {
                let out = take(dst, rows * layer.out_dim);
                layer.forward(src, rows, out);
                relu_inplace(out);
                current_in_a = !current_in_a;
            }
        }
    }
}
