//! Layer normalisation.

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
            let mean = row.iter().sum::<f32>() / dim as f32;
            let var = row.iter().map(|v| (v - mean) * (v - mean)).sum::<f32>() / dim as f32;
            let inv = 1.0 / (var + self.eps).sqrt();
            for ((v, g), b) in row.iter_mut().zip(&self.gamma).zip(&self.beta) {
                *v = (*v - mean) * inv * g + b;
            }
        }
    }
}
