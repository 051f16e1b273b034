//! The seven lapped-solid-texture types (thesis ch. 3): anisotropy level x variation level.
//!
//! ```text
//!                 variation 0   1     2     3
//! anisotropy 0       T0
//! anisotropy 1       T1a       T1b
//! anisotropy 2       T2a       T2b   T2c   T2d
//! ```
//! Variation is limited by anisotropy, so these seven are all there are.

use crate::error::{Error, Result};
use std::fmt;
use std::str::FromStr;

/// One of the seven texture types.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum TextureType {
    /// Isotropic: every cut looks alike (granite, gravel).
    T0,
    /// One axis, homogeneous (long-grain wood, fibres).
    T1a,
    /// One axis, varies along it: layered (strata, cake, tree rings).
    T1b,
    /// Three distinct cut appearances, homogeneous (plywood, bricks).
    T2a,
    /// Three distinct appearances, varies along one direction (kiwi, carrot, trunk).
    T2b,
    /// Varies along two directions.
    T2c,
    /// Varies along all three directions.
    T2d,
}

impl TextureType {
    /// All seven, in table order.
    pub const ALL: [TextureType; 7] = [
        TextureType::T0,
        TextureType::T1a,
        TextureType::T1b,
        TextureType::T2a,
        TextureType::T2b,
        TextureType::T2c,
        TextureType::T2d,
    ];

    /// How many distinct cross-section appearances there are, minus one (0, 1 or 2).
    pub fn anisotropy(self) -> u8 {
        match self {
            TextureType::T0 => 0,
            TextureType::T1a | TextureType::T1b => 1,
            _ => 2,
        }
    }

    /// How many directions the pattern changes gradually along (0..=3).
    pub fn variation(self) -> u8 {
        match self {
            TextureType::T0 | TextureType::T1a | TextureType::T2a => 0,
            TextureType::T1b | TextureType::T2b => 1,
            TextureType::T2c => 2,
            TextureType::T2d => 3,
        }
    }

    /// The type with these levels, if the pair is one of the seven.
    pub fn from_levels(anisotropy: u8, variation: u8) -> Option<TextureType> {
        Self::ALL.into_iter().find(|t| t.anisotropy() == anisotropy && t.variation() == variation)
    }

    /// The thesis' name: `0`, `1-a`, `1-b`, `2-a` ... `2-d`.
    pub fn name(self) -> &'static str {
        match self {
            TextureType::T0 => "0",
            TextureType::T1a => "1-a",
            TextureType::T1b => "1-b",
            TextureType::T2a => "2-a",
            TextureType::T2b => "2-b",
            TextureType::T2c => "2-c",
            TextureType::T2d => "2-d",
        }
    }

    /// In how many dimensions a volume of this type tiles (3 - variation).
    pub fn tiling_dimensions(self) -> u8 {
        3 - self.variation()
    }

    /// What orients a patch of this type in a model (thesis ch. 5).
    pub fn tensor_field(self) -> &'static str {
        match self {
            TextureType::T0 => "none: each patch gets a random orientation",
            TextureType::T1a => "a vector field from strokes (the fibre axis); the other axes random",
            TextureType::T1b => "the gradient of a depth field (the layer normal); the other axes random",
            TextureType::T2a => "a full tensor field: depth gradient plus stroke directions",
            TextureType::T2b => "depth gradient plus stroke directions; the depth field itself is kept",
            TextureType::T2c | TextureType::T2d => "a tensor field plus two (2-c) or three (2-d) coordinate fields",
        }
    }

    /// How the filler pastes patches of this type.
    pub fn filling(self) -> &'static str {
        match self {
            TextureType::T0 | TextureType::T1a | TextureType::T2a => {
                "splotch mask, user-set scale, any depth: pasted until every tetrahedron is covered"
            }
            TextureType::T1b | TextureType::T2b => {
                "outer/middle/inner masks by depth; scale 1/|grad depth| so the skin lands on the surface"
            }
            TextureType::T2c | TextureType::T2d => {
                "not lapped: every patch would have to sit at the same place in the exemplar along the \
                 axes it varies on, so copies of its one-of-a-kind parts would land all over the model \
                 (docs/fill.md); fill the tileable part as 2-b and stamp the rest"
            }
        }
    }

    /// Examples from the thesis.
    pub fn examples(self) -> &'static str {
        match self {
            TextureType::T0 => "granite, gravel, sponge",
            TextureType::T1a => "long-grain wood, fibres, muscle",
            TextureType::T1b => "strata, cake layers",
            TextureType::T2a => "plywood, bricks",
            TextureType::T2b => "kiwi, carrot, tree trunk",
            TextureType::T2c => "(few real examples)",
            TextureType::T2d => "(few real examples)",
        }
    }
}

impl fmt::Display for TextureType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for TextureType {
    type Err = Error;

    /// Accepts `0`, `1-a`, `1a`, `T1a`, `2-b` ... case-insensitively.
    fn from_str(text: &str) -> Result<Self> {
        let key: String = text
            .trim()
            .trim_start_matches(['t', 'T'])
            .chars()
            .filter(|c| *c != '-')
            .collect::<String>()
            .to_ascii_lowercase();
        Self::ALL.into_iter().find(|t| t.name().replace('-', "") == key).ok_or_else(|| {
            Error::invalid(format!("unknown texture type {text:?}; allowed: 0, 1-a, 1-b, 2-a, 2-b, 2-c, 2-d"))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_round_trip_and_limit_variation() {
        for t in TextureType::ALL {
            assert_eq!(TextureType::from_levels(t.anisotropy(), t.variation()), Some(t));
            assert!(t.variation() <= t.anisotropy().max(1) + u8::from(t.anisotropy() == 2));
        }
        assert_eq!(TextureType::from_levels(0, 1), None);
        assert_eq!(TextureType::from_levels(1, 2), None);
    }

    #[test]
    fn parses_the_thesis_names() {
        assert_eq!("1-b".parse::<TextureType>().unwrap(), TextureType::T1b);
        assert_eq!("T2a".parse::<TextureType>().unwrap(), TextureType::T2a);
        assert_eq!("0".parse::<TextureType>().unwrap(), TextureType::T0);
        let err = "3-a".parse::<TextureType>().unwrap_err().to_string();
        assert!(err.contains("3-a") && err.contains("allowed"), "{err}");
    }
}
