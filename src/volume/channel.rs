//! Channel roles: what each sample of a voxel means.

use crate::error::{Error, Result};
use std::fmt;

/// The role of one channel of a volume or image.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum Channel {
    /// Red.
    R,
    /// Green.
    G,
    /// Blue.
    B,
    /// Alpha (coverage, mask).
    A,
    /// Depth for layered textures: 0 at the outside, 1 at the core.
    Depth,
    /// Displacement (height) for displacement mapping.
    Displacement,
    /// Any other named channel (feature distance, labels ...).
    Named(String),
}

impl Channel {
    /// `[R, G, B]`.
    pub fn rgb() -> Vec<Channel> {
        vec![Channel::R, Channel::G, Channel::B]
    }

    /// `[R, G, B, A]`.
    pub fn rgba() -> Vec<Channel> {
        vec![Channel::R, Channel::G, Channel::B, Channel::A]
    }

    /// A single grey channel, stored as `R`.
    pub fn grey() -> Vec<Channel> {
        vec![Channel::R]
    }

    /// The channel's name in files: `R`, `G`, `B`, `A`, `Depth`, `Displacement` or its own.
    pub fn name(&self) -> &str {
        match self {
            Channel::R => "R",
            Channel::G => "G",
            Channel::B => "B",
            Channel::A => "A",
            Channel::Depth => "Depth",
            Channel::Displacement => "Displacement",
            Channel::Named(name) => name,
        }
    }

    /// The role for a name; unknown names become [`Channel::Named`] if they are valid.
    pub fn parse(name: &str) -> Result<Channel> {
        Ok(match name {
            "R" => Channel::R,
            "G" => Channel::G,
            "B" => Channel::B,
            "A" => Channel::A,
            "Depth" => Channel::Depth,
            "Displacement" => Channel::Displacement,
            other => {
                let ok = !other.is_empty()
                    && other.len() <= 31
                    && other.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '.');
                if !ok {
                    return Err(Error::invalid(format!(
                        "channel name {other:?} is not allowed: use 1-31 ASCII letters, digits, '_' or '.'"
                    )));
                }
                Channel::Named(other.to_string())
            }
        })
    }

    /// Parse a comma-separated list such as `R,G,B,Depth`.
    pub fn parse_list(text: &str) -> Result<Vec<Channel>> {
        let list = text.split(',').map(|s| Channel::parse(s.trim())).collect::<Result<Vec<_>>>()?;
        Channel::check_list(&list)?;
        Ok(list)
    }

    /// A list must be non-empty and free of duplicates.
    pub fn check_list(list: &[Channel]) -> Result<()> {
        if list.is_empty() {
            return Err(Error::invalid("a channel list must name at least one channel"));
        }
        for (i, c) in list.iter().enumerate() {
            if list[..i].contains(c) {
                return Err(Error::invalid(format!("channel {} appears twice in {}", c.name(), join(list))));
            }
        }
        Ok(())
    }
}

/// The grey value of an R, G, B colour, for a volume or image with one colour channel:
/// luminance with the Rec. 709 weights 0.2126, 0.7152, 0.0722, the weights the fill's
/// pictures and the web viewer use for grey.
pub fn luminance([r, g, b]: [f32; 3]) -> f32 {
    0.2126 * r + 0.7152 * g + 0.0722 * b
}

/// `R,G,B` for a list of channels.
pub fn join(list: &[Channel]) -> String {
    list.iter().map(Channel::name).collect::<Vec<_>>().join(",")
}

impl fmt::Display for Channel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        let list = Channel::parse_list("R,G,B,A,Depth,Displacement,feature_dist").unwrap();
        assert_eq!(list[6], Channel::Named("feature_dist".into()));
        assert_eq!(join(&list), "R,G,B,A,Depth,Displacement,feature_dist");
    }

    #[test]
    fn bad_lists_are_refused() {
        assert!(Channel::parse_list("R,R").unwrap_err().to_string().contains("twice"));
        assert!(Channel::parse("a b").unwrap_err().to_string().contains("\"a b\""));
        assert!(Channel::check_list(&[]).is_err());
    }
}
