//! Integration tests: file formats, bad input, and the command line.

mod bad_input;
mod classify;
mod cli;
mod fill;
mod formats;
mod fuzz;
mod handmade;
mod library;
mod masks;
mod ranges;
mod safety;
mod mesh;
mod snapshots;
mod support;
mod synth;
mod tour;
