//! The exemplar library, shared by both front ends: a manifest's entries made into volumes
//! ([`recipe`]), the files each entry produces ([`files`]), the cache and the plan of what
//! is stale and why ([`cache`]), the build with its progress, cancellation and report
//! ([`build`]), and the exemplars a fill spec names, resolved from a built library
//! ([`fill`], also the fill preview).
//!
//! It sits above [`crate::io`] and the core: it reads and writes files (the manifest's
//! inputs, the output folder, its cache), but never the terminal; what happens is told to
//! a [`crate::progress::Progress`] or a [`build::Observer`], which may also cancel.

pub mod build;
pub mod cache;
pub mod files;
pub mod fill;
pub mod guided;
pub mod previous;
pub mod recipe;

pub use build::{Observer, Outcome, Request};
pub use cache::{Freshness, Record};
