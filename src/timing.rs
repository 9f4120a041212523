//! A millisecond clock that works natively and, when the binding installs one, in wasm.
//!
//! `std::time::Instant` panics on `wasm32-unknown-unknown`, and the core must not depend on
//! wasm-bindgen; so the clock is a plain function pointer. Natively it defaults to a monotonic
//! `Instant`; the wasm binding passes `performance.now()`. Without a clock, timings read 0.

/// A clock: milliseconds from an arbitrary origin.
pub type Clock = fn() -> f64;

/// The default clock of this target (`None` on wasm32, where the binding provides one).
pub fn default_clock() -> Option<Clock> {
    #[cfg(not(target_arch = "wasm32"))]
    {
        Some(native_now_ms)
    }
    #[cfg(target_arch = "wasm32")]
    {
        None
    }
}

#[cfg(not(target_arch = "wasm32"))]
fn native_now_ms() -> f64 {
    use std::sync::OnceLock;
    use std::time::Instant;
    static ORIGIN: OnceLock<Instant> = OnceLock::new();
    ORIGIN.get_or_init(Instant::now).elapsed().as_secs_f64() * 1e3
}

/// Measures consecutive stages with an optional clock.
#[derive(Clone, Copy, Debug)]
pub struct Stopwatch {
    clock: Option<Clock>,
    last: f64,
}

impl Stopwatch {
    /// Starts now.
    pub fn start(clock: Option<Clock>) -> Self {
        Self { clock, last: clock.map_or(0.0, |c| c()) }
    }

    /// Milliseconds since the previous lap (or the start); 0 without a clock.
    pub fn lap(&mut self) -> f64 {
        match self.clock {
            Some(c) => {
                let now = c();
                let d = now - self.last;
                self.last = now;
                d.max(0.0)
            }
            None => 0.0,
        }
    }
}
