//! Layer normalisation.

/// `sum_i f(x_i)` with 16 lane-wise partial sums (vectorisable).
#[inline(always)]
fn lane_sum(x: &[f32], f: impl Fn(f32) -> f32) -> f32 {
    let mut acc = [0.0f32; 16];
    let mut chunks = x.chunks_exact(16);
    for c in &mut chunks {
        for (v, a) in c.iter().zip(acc.iter_mut()) {
            *a += f(*v);
        }
    }
    let tail: f32 = chunks.remainder().iter().map(|v| f(*v)).sum();
    acc.iter().sum::<f32>() + tail
}

/// LayerNorm over the last dimension: `y = (x - mean) / sqrt(var + eps) * gamma + beta`.
#[derive(Clone, Debug, PartialEq)]
pub struct LayerNorm {
    /// Scale, `[dim]`.
    pub gamma: Vec<f32>,
    /// Shift, `[dim]`.
    pub beta: Vec<f32>,
    /// Variance epsilon.
    pub eps: f32,
}

impl LayerNorm {
    /// Normalises each row of a row-major `[rows, dim]` buffer in place.
    pub fn forward_inplace(&self, x: &mut [f32]) {
        let dim = self.gamma.len();
        for row in x.chunks_exact_mut(dim) {
            self.row(row);
        }
    }

    /// `x = LayerNorm(x + residual)` row by row, in place (`residual` has the shape of `x`).
    pub fn forward_residual_inplace(&self, x: &mut [f32], residual: &[f32]) {
        let dim = self.gamma.len();
        debug_assert_eq!(x.len(), residual.len());
        for (row, res) in x.chunks_exact_mut(dim).zip(residual.chunks_exact(dim)) {
            for (v, r) in row.iter_mut().zip(res) {
                *v += r;
            }
            self.row(row);
        }
    }

    #[inline]
    fn row(&self, row: &mut [f32]) {
        let dim = row.len();
        if dim == 0 {
            return;
        }
        // Two passes around the first element as a shift: exact for a constant row (mean = x0,
        // var = 0, so the output is beta) and no cancellation for rows far from 0.
        let x0 = row[0];
        let inv_n = 1.0 / dim as f32;
        let mean = x0 + lane_sum(row, |v| v - x0) * inv_n;
        let var = lane_sum(row, |v| (v - mean) * (v - mean)) * inv_n;
        let inv = 1.0 / (var + self.eps).sqrt();
        for ((v, g), b) in row.iter_mut().zip(&self.gamma).zip(&self.beta) {
            *v = (*v - mean) * inv * g + b;
        }
    }
}
