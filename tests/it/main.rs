//! Integration tests: file formats, bad input, and the command line.

mod bad_input;
mod cli;
mod formats;
mod support;
mod synth;
