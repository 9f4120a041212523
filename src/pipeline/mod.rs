//! The registration pipeline of [`crate::Registrar::register_with_progress`] as typed stages, each
//! taking the previous one's output:
//!
//! 1. [`options`]: the caller's [`crate::Options`] checked and resolved ([`options::Resolved`]).
//! 2. [`prepare`]: the validated clouds in their local, jointly normalised frames, sampled for the
//!    network and voxelised for ICP ([`prepare::Prepared`]); the target's share
//!    ([`target::PreparedTarget`]) is kept by the registrar and reused for the same target.
//! 3. [`network`]: the network + GMR estimate in normalised units.
//! 4. [`starts`]: the stages of the search and the candidate starts of each ([`starts::Starts`]).
//! 5. [`search`]: the adaptive or exhaustive refinement of the starts, with the confidence stop,
//!    and the other poses that fit about as well ([`search::Chosen`]); [`caps`] holds down the
//!    confidence of answers whose fit cannot confirm their pose, and of answers a mirror image of
//!    the source fits clearly better than ([`mirror`]); with `icpLoss: "robust"`, [`robust`]
//!    polishes the answer with a changed surface weighed down.
//!    With `up` ([`crate::Options::up`]), [`upright`] levels its starts and rules out tilted
//!    answers and look-alikes.
//! 6. [`result`]: the chosen answer and its alternatives mapped back to the caller's frame and
//!    units, checked, with its warnings ([`crate::Registration`]).

pub(crate) mod caps;
pub(crate) mod mirror;
pub(crate) mod network;
pub(crate) mod options;
pub(crate) mod prepare;
pub(crate) mod result;
pub(crate) mod robust;
pub(crate) mod search;
pub(crate) mod starts;
pub(crate) mod target;
pub(crate) mod upright;
pub(crate) mod wall;
