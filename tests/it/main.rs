//! Integration tests: file formats, bad input, and the command line.

mod bad_input;
mod cli;
mod formats;
mod handmade;
mod mesh;
mod support;
mod synth;
