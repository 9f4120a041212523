//! # arps
//!
//! Partial-to-partial 3D point-cloud registration: DGMR-ARPS (attention-guided reference point
//! shifting + Gaussian mixture registration) followed by ICP, in pure Rust, for native targets
//! and WebAssembly.
//!
//! ```no_run
//! use arps::{io, Options, Registrar, Weights, ModelConfig};
//! let source = io::read_point_cloud(&std::fs::read("source.ply")?, "source.ply")?;
//! let target = io::read_point_cloud(&std::fs::read("target.ply")?, "target.ply")?;
//! let mut registrar = Registrar::new(&Weights::random(&ModelConfig::web(), 0)?)?;
//! let result = registrar.register(&source, &target, &Options::default())?;
//! println!("{}", result.T_target_source); // maps source points into the target frame
//! # Ok::<(), arps::Error>(())
//! ```
//!
//! Conventions (frames, the 4x4 layout) are documented once, in [`transform`].
//!
//! Features: `embed-model` (default) embeds the default model (`Registrar::with_default_model`,
//! [`weights::DEFAULT_MODEL`]); without it the library loads models from bytes only, as the npm
//! package's engine does. `cli` and `train` build the command-line tools.

#![warn(missing_docs)]

pub mod checks;
pub mod cloud;
pub mod confidence;
pub mod contract;
#[cfg(feature = "cli")]
pub mod data;
pub mod error;
pub mod global;
pub mod gmr;
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
pub mod support;
pub mod timing;
#[cfg(feature = "train")]
pub mod train;
pub mod transform;
#[cfg(target_arch = "wasm32")]
pub mod wasm;
pub mod weights;

pub use cloud::{NonFinite, PointCloud};
pub use error::{Error, Result};
pub use icp::IcpKind;
pub use model::{Model, ModelConfig};
pub use outliers::Outliers;
pub use refine::Start;
pub use register::{Alternative, Options, Registrar, Registration, Search, Stage, Timings};
pub use support::Support;
pub use weights::{StoreAs, Weights};
