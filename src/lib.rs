//! # arps
//!
//! Partial-to-partial 3D point-cloud registration: DGMR-ARPS (attention-guided reference point
//! shifting + Gaussian mixture registration) followed by ICP, in pure Rust, for native targets
//! and WebAssembly.
//!
//! ```no_run
//! use arps::{io, Options, Registrar};
//! let source = io::read_path("source.ply".as_ref())?;
//! let target = io::read_path("target.ply".as_ref())?;
//! let mut registrar = Registrar::with_default_model()?; // the embedded, trained model
//! let result = registrar.register(&source, &target, &Options::default())?;
//! println!("{}", result.T_target_source); // maps source points into the target frame
//! if result.confidence < 0.5 {
//!     eprintln!("likely wrong: {:?}", result.warnings);
//! }
//! # Ok::<(), arps::Error>(())
//! ```
//!
//! Conventions (frames, the 4x4 layout) are documented once, in [`transform`]. Clouds whose
//! coordinates lie far from zero (a map grid) keep their digits when built from `f64`
//! ([`PointCloud::from_points_f64`], or read from a file); `f32` coordinates have already lost
//! them. Errors and warnings name options by their JSON / JS names (`voxelSize`), the names
//! [`Options`] has in serde.
//!
//! Features: `embed-model` (default) embeds the default model (`Registrar::with_default_model`,
//! [`weights::DEFAULT_MODEL`]); without it the library loads models from bytes only, as the npm
//! package's engine does. `cli` and `train` build the command-line tools.
//!
//! Speed: the engine's kernels need an optimised build. In a debug build a registration takes
//! 30 to 50 times as long; to keep your own code in debug, optimise the dependencies in your
//! `Cargo.toml`:
//!
//! ```toml
//! [profile.dev.package."*"]
//! opt-level = 3
//! ```

#![warn(missing_docs)]

pub mod cancel;
pub mod checks;
pub mod cloud;
pub mod confidence;
pub mod contract;
#[cfg(feature = "cli")]
pub mod data;
pub mod error;
pub mod global;
pub mod gmr;
pub mod grain;
pub mod icp;
pub mod io;
pub mod limits;
pub mod model;
pub mod nn;
pub mod normals;
pub mod origin;
pub mod outliers;
mod pipeline;
pub mod refine;
pub mod register;
pub mod rigid;
pub mod sampling;
pub mod spacing;
pub mod spatial;
mod stats;
pub mod support;
pub mod timing;
#[cfg(feature = "train")]
pub mod train;
pub mod transform;
pub mod warning;
#[cfg(target_arch = "wasm32")]
pub mod wasm;
pub mod weights;

pub use cancel::Cancel;
pub use cloud::{NonFinite, PointCloud};
pub use confidence::Evidence;
pub use error::{Error, Result};
pub use icp::{IcpKind, IcpLoss};
pub use model::{Model, ModelConfig};
pub use outliers::Outliers;
pub use refine::Start;
pub use register::{Alternative, FreeMotion, FreeMotionKind, Options, Registrar, Registration, Search, Stage, Timings};
pub use support::Support;
pub use warning::{Warning, WarningCode};
pub use weights::{StoreAs, Weights};
