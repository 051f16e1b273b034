//! # solidtex
//!
//! Author **solid texture exemplars** (small 3D colour volumes whose every cut looks
//! like a real material) and fill 3D models with them by **lapped solid textures**.
//!
//! ```text
//!  2D photos / cross-sections --> sweep (+noise, +skin) --+
//!  seed meshes (OBJ/STL/PLY) ---> stamp ------------------+--> Volume --> classify
//!  2D exemplars (Ex, Ey, Ez) ---> synthesize (Kopf 2007) -+      |
//!  procedural recipes ----------> marble, strata, wood, ..+      +--> masks
//!                                                                v
//!              exemplar library (manifest + built files) --> fill backend --> cuts
//! ```
//!
//! The core ([`volume`], [`synth`], [`fill`], [`render`] and the other algorithm modules
//! that `.ci/run` lists) is pure: plain data in, plain data out, an explicit seed for
//! anything random. [`io`] reads and writes files; [`library`] builds a manifest's
//! exemplars into an output folder (recipes, cache, reports) for both front ends, [`cli`]
//! and [`tui`], which also talk to the terminal.
//!
//! A 16³ volume, a slice and its statistics:
//!
//! ```
//! use solidtex::volume::{Axis, Channel, Volume};
//!
//! let v = Volume::from_fn([16, 16, 16], Channel::rgb(), |x, y, z, out| {
//!     out.copy_from_slice(&[x as f32 / 15.0, y as f32 / 15.0, z as f32 / 15.0]);
//! })?;
//! let cut = v.slice(Axis::Z, 8)?;
//! assert_eq!((cut.width(), cut.height()), (16, 16));
//! assert_eq!(cut.pixel(15, 0), &[1.0, 0.0, 8.0 / 15.0]);
//! let stats = v.channel_stats(8);
//! assert!((stats[0].mean - 0.5).abs() < 1e-6);
//! # Ok::<(), solidtex::Error>(())
//! ```

#![deny(unsafe_code)]
#![warn(missing_docs)]

pub mod classify;
pub mod cli;
pub mod controls;
pub mod correlation;
pub mod error;
pub mod fill;
pub mod ground_truth;
pub mod guided;
pub mod hashing;
pub mod io;
pub mod labels;
pub mod library;
pub mod lines;
pub mod mask;
pub mod mesh;
pub mod noise;
pub mod procedural;
pub mod progress;
pub mod quality;
pub mod render;
pub mod sections;
pub mod sharpness;
pub mod snapshot;
pub mod stamp;
pub mod surface;
pub mod sweep;
pub mod synth;
pub mod texture_type;
pub mod tui;
pub mod volume;

pub use error::{Error, Result};
pub use texture_type::TextureType;
pub use volume::{Channel, Volume};
