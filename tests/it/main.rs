//! Integration tests: file formats, bad input, and the command line.

mod bad_input;
mod classify;
mod cli;
mod coordinates;
mod export;
mod fill;
mod formats;
mod fuzz;
mod guided;
mod handmade;
mod labelled;
mod library;
mod masks;
mod mesh;
mod outputs;
mod ranges;
mod safety;
mod snapshots;
mod support;
mod surface;
mod synth;
mod tour;
mod web;
mod yardstick;
