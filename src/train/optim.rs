//! Adam, the parameters' moving average, gradient-norm clipping, and the finiteness check.

use super::model::Params;
use serde::{Deserialize, Serialize};

/// Adam (Kingma & Ba) with bias correction. Its moments are plain maps by parameter name, so a
/// checkpoint is just `Params` + this struct.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Adam {
    /// Learning rate.
    pub lr: f32,
    /// First-moment decay (0.9).
    pub beta1: f32,
    /// Second-moment decay (0.999).
    pub beta2: f32,
    /// Denominator epsilon (1e-8).
    pub eps: f32,
    /// Number of updates applied so far.
    pub t: u64,
    /// First moments.
    pub m: Params,
    /// Second moments.
    pub v: Params,
}

impl Adam {
    /// Adam with the usual betas (0.9, 0.999) and eps 1e-8.
    pub fn new(lr: f32) -> Self {
        Self { lr, beta1: 0.9, beta2: 0.999, eps: 1e-8, t: 0, m: Params::new(), v: Params::new() }
    }

    /// One update `p -= lr * m_hat / (sqrt(v_hat) + eps)` for every parameter with a gradient.
    pub fn update(&mut self, params: &mut Params, grads: &Params) {
        self.t += 1;
        let (b1, b2) = (self.beta1, self.beta2);
        let c1 = 1.0 - (b1 as f64).powi(self.t as i32);
        let c2 = 1.0 - (b2 as f64).powi(self.t as i32);
        let step = (self.lr as f64 / c1) as f32;
        let inv_c2 = (1.0 / c2) as f32;
        for (name, p) in params.iter_mut() {
            let Some(g) = grads.get(name) else { continue };
            let m = self.m.entry(name.clone()).or_insert_with(|| vec![0.0; p.len()]);
            let v = self.v.entry(name.clone()).or_insert_with(|| vec![0.0; p.len()]);
            for (((p, g), m), v) in p.iter_mut().zip(g).zip(m.iter_mut()).zip(v.iter_mut()) {
                *m = b1 * *m + (1.0 - b1) * g;
                *v = b2 * *v + (1.0 - b2) * g * g;
                *p -= step * *m / ((*v * inv_c2).sqrt() + self.eps);
            }
        }
    }
}

/// An exponential moving average of the parameters (Polyak averaging): after every update,
/// `avg = decay * avg + (1 - decay) * params`. It smooths the iterate's step-to-step noise at no
/// cost in steps (whether it also scores better depends on the learning rate: `models/MODEL.md`,
/// session 6); validation and export use it when a run keeps one.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Ema {
    /// Weight of the old average per update (e.g. 0.999: a horizon of about 1,000 steps).
    pub decay: f32,
    /// The averaged parameters.
    pub params: Params,
}

impl Ema {
    /// An average that starts at `params`.
    pub fn new(decay: f32, params: &Params) -> Self {
        Self { decay, params: params.clone() }
    }

    /// Folds the current parameters into the average. A parameter the average does not hold yet
    /// starts at its current value.
    pub fn update(&mut self, params: &Params) {
        let d = self.decay;
        for (name, p) in params {
            match self.params.get_mut(name) {
                Some(a) if a.len() == p.len() => {
                    for (a, &p) in a.iter_mut().zip(p) {
                        *a = d * *a + (1.0 - d) * p;
                    }
                }
                _ => {
                    self.params.insert(name.clone(), p.clone());
                }
            }
        }
    }
}

/// Global L2 norm of all gradients (accumulated in `f64`; NaN/inf propagate).
pub fn grad_norm(grads: &Params) -> f64 {
    grads.values().flatten().map(|&g| (g as f64) * (g as f64)).sum::<f64>().sqrt()
}

/// Scales all gradients so their global norm is at most `max_norm`. Returns the norm before
/// clipping and whether it clipped.
pub fn clip_grad_norm(grads: &mut Params, max_norm: f64) -> (f64, bool) {
    let norm = grad_norm(grads);
    if norm.is_finite() && norm > max_norm && max_norm > 0.0 {
        let s = (max_norm / norm) as f32;
        for g in grads.values_mut().flatten() {
            *g *= s;
        }
        (norm, true)
    } else {
        (norm, false)
    }
}
