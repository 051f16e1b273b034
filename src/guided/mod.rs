//! Sketch-guided solid texturing (Zhang et al. 2011): a smooth frame field inside a model
//! from the designer's strokes and depth ([`field`]: harmonic interpolation of quaternions
//! on the tet mesh), and a solid texture synthesized along it on demand by the project's
//! coordinate core ([`crate::synth::coords`]: only the voxels a cut or the whole solid
//! needs, [`crate::synth::region`]).

pub mod field;
pub mod regions;
pub mod solid;
