//! Stopping a registration from another thread ([`Cancel`],
//! [`Registrar::register_cancellable`](crate::Registrar::register_cancellable)).
//!
//! The registration's loops that can run long (each ICP iteration, each RANSAC draw) look at the
//! handle of the call running on their thread, and stop early once it is cancelled; the call then
//! returns [`Error::Cancelled`](crate::Error::Cancelled), whatever it had found. A call that is
//! not cancelled runs exactly as it would without a handle (the same answer, bit for bit).

use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// A handle that cancels the registrations it is given to: clone it, pass one to
/// [`Registrar::register_cancellable`](crate::Registrar::register_cancellable), and call
/// [`Cancel::cancel`] on another from any thread (a deadline, a client that went away). Once
/// cancelled it stays so: use a new handle for the next call.
#[derive(Clone, Debug, Default)]
pub struct Cancel(Arc<AtomicBool>);

impl Cancel {
    /// A handle not cancelled yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Cancels every registration given this handle (or a clone of it): running ones stop at
    /// their next ICP iteration or RANSAC draw and return [`Error::Cancelled`](crate::Error::Cancelled),
    /// later ones return it at once.
    pub fn cancel(&self) {
        self.0.store(true, Ordering::Relaxed);
    }

    /// Whether [`Cancel::cancel`] was called on this handle or a clone of it.
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }
}

thread_local! {
    /// The handle of the registration running on this thread, if it was given one.
    static CURRENT: RefCell<Option<Cancel>> = const { RefCell::new(None) };
}

/// Whether the registration running on this thread was cancelled (false without a handle).
pub(crate) fn cancelled() -> bool {
    CURRENT.with(|c| c.borrow().as_ref().is_some_and(Cancel::is_cancelled))
}

/// Runs `f` with `cancel` as this thread's handle (the previous one restored after, also when
/// `f` unwinds).
pub(crate) fn during<T>(cancel: &Cancel, f: impl FnOnce() -> T) -> T {
    struct Restore(Option<Cancel>);
    impl Drop for Restore {
        fn drop(&mut self) {
            let previous = self.0.take();
            CURRENT.with(|c| *c.borrow_mut() = previous);
        }
    }
    let _restore = Restore(CURRENT.with(|c| c.borrow_mut().replace(cancel.clone())));
    f()
}
