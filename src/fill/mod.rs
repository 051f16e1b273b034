//! The lapped-solid-textures filling backend (thesis ch. 6): a closed triangle mesh becomes
//! a tetrahedral mesh, a tensor field is built from the fill spec's constraints, exemplar
//! patches are pasted along the field until every tet is covered, and the result — an
//! [`LstModel`](model::LstModel) — renders planar cuts and bakes to a volume.

pub mod mesher;
pub mod tets;
