//! Sketch-guided solid texturing (Zhang et al. 2011): a smooth frame field inside a model
//! from the designer's strokes and depth, along which a solid texture is to be synthesized.
//! So far the field ([`field`]): harmonic interpolation of quaternions on the tet mesh, and
//! its picture on a cut.

pub mod field;
