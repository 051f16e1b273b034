//! Small value parsers for command-line options and manifest fields; every error names
//! the option or field, the value and what is allowed.
//!
//! `label` is how the value is named in a message: `--count` on the command line,
//! `count =` in a manifest, so that an error reads `--count 9000 is out of range` or
//! `count = 9000 is out of range`.

use crate::error::{Error, Result};
use glam::{Quat, Vec3};
use std::fmt::Display;

/// Largest distance from the origin of a position, in voxels.
pub use crate::stamp::POSITION_LIMIT;

/// `value` if it lies in `min..=max` (NaN never does), else an error naming `label`,
/// the value and the range.
pub fn within<T: PartialOrd + Display + Copy>(label: &str, value: T, min: T, max: T) -> Result<T> {
    if value >= min && value <= max {
        Ok(value)
    } else {
        Err(Error::invalid(format!("{label} {value} is out of range; allowed: {min} to {max}")))
    }
}

/// A mask fall-off: the width of the soft band as a share of the mask size, over 0 and under 0.5.
pub fn falloff(label: &str, value: f32) -> Result<f32> {
    if value > 0.0 && value < 0.5 {
        Ok(value)
    } else {
        Err(Error::invalid(format!("{label} {value} is out of range; allowed: over 0 and under 0.5")))
    }
}

/// Comma-separated numbers, exactly `n` of them (or any of `ns`).
pub fn numbers(option: &str, text: &str, ns: &[usize]) -> Result<Vec<f32>> {
    let values: std::result::Result<Vec<f32>, _> = text.split(',').map(|s| s.trim().parse::<f32>()).collect();
    match values {
        Ok(v) if ns.contains(&v.len()) && v.iter().all(|x| x.is_finite()) => Ok(v),
        Ok(v) if ns.contains(&v.len()) => {
            let (i, _) = v.iter().enumerate().find(|(_, x)| !x.is_finite()).expect("a value that is not finite");
            let given = text.split(',').nth(i).unwrap_or_default().trim();
            Err(Error::invalid(format!(
                "{option} {text:?}: {given} is not a finite number (too large, or not a number)"
            )))
        }
        _ => Err(Error::invalid(format!(
            "{option} {text:?} is not {} comma-separated numbers",
            ns.iter().map(|n| n.to_string()).collect::<Vec<_>>().join(" or ")
        ))),
    }
}

/// `X,Y,Z`, each within [`POSITION_LIMIT`] of 0.
pub fn point(option: &str, text: &str) -> Result<Vec3> {
    let v = numbers(option, text, &[3])?;
    positions(option, text, &v)?;
    Ok(Vec3::new(v[0], v[1], v[2]))
}

/// Every coordinate of `v` within [`POSITION_LIMIT`] of 0.
pub fn positions(option: &str, text: &str, v: &[f32]) -> Result<()> {
    if v.iter().all(|x| x.abs() <= POSITION_LIMIT) {
        Ok(())
    } else {
        Err(Error::invalid(format!(
            "{option} {text:?} is out of range; allowed: each coordinate -{POSITION_LIMIT} to {POSITION_LIMIT}"
        )))
    }
}

/// `R,G,B` in 0..1, or `#rrggbb`.
pub fn colour(option: &str, text: &str) -> Result<[f32; 3]> {
    if let Some(hex) = text.strip_prefix('#') {
        let byte = |i: usize| u8::from_str_radix(hex.get(i..i + 2).unwrap_or("x"), 16);
        if let (6, Ok(r), Ok(g), Ok(b)) = (hex.len(), byte(0), byte(2), byte(4)) {
            return Ok([r, g, b].map(|c| c as f32 / 255.0));
        }
        return Err(Error::invalid(format!("{option} {text:?} is not a colour like #a0c040")));
    }
    let v = numbers(option, text, &[3])?;
    if v.iter().any(|c| !(0.0..=1.0).contains(c)) {
        return Err(Error::invalid(format!("{option} {text:?}: colour values must lie in 0..1 (or use #rrggbb)")));
    }
    Ok([v[0], v[1], v[2]])
}

/// `AX,AY,AZ,DEG`: a rotation of DEG degrees (-360 to 360) about the axis (AX, AY, AZ),
/// whose components lie within [`POSITION_LIMIT`] of 0 and are not all 0.
pub fn rotation(option: &str, text: &str) -> Result<Quat> {
    let v = numbers(option, text, &[4])?;
    positions(option, text, &v[..3])?;
    within(&format!("{option} angle"), v[3], -360.0, 360.0)?;
    let axis = Vec3::new(v[0], v[1], v[2]);
    let axis =
        axis.try_normalize().ok_or_else(|| Error::invalid(format!("{option} {text:?}: the axis is too short to give a direction (zero, or under about 1e-19 in every component)")))?;
    Ok(Quat::from_axis_angle(axis, v[3].to_radians()))
}

/// `S` or `SX,SY,SZ`, each in `min..=max`.
pub fn scale(option: &str, text: &str, min: f32, max: f32) -> Result<Vec3> {
    let v = numbers(option, text, &[1, 3])?;
    if v.iter().any(|s| !(min..=max).contains(s)) {
        return Err(Error::invalid(format!("{option} {text:?} is out of range; allowed: each scale {min} to {max}")));
    }
    Ok(if v.len() == 1 { Vec3::splat(v[0]) } else { Vec3::new(v[0], v[1], v[2]) })
}

/// `LOW..HIGH` (or a single number), with `min <= LOW <= HIGH <= max`.
pub fn range(option: &str, text: &str, min: f32, max: f32) -> Result<(f32, f32)> {
    let parts: Vec<&str> = text.split("..").collect();
    let bad = || Error::invalid(format!("{option} {text:?} is not a range like 1.5..3"));
    let nums: Vec<f32> = parts.iter().map(|p| p.trim().parse::<f32>().map_err(|_| bad())).collect::<Result<_>>()?;
    let (low, high) = match nums.as_slice() {
        [a] => (*a, *a),
        [a, b] if a <= b => (*a, *b),
        _ => return Err(bad()),
    };
    if !(min..=max).contains(&low) || !(min..=max).contains(&high) {
        return Err(Error::invalid(format!("{option} {text:?} is out of range; allowed: {min} to {max}")));
    }
    Ok((low, high))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_names_the_option() {
        assert_eq!(point("--at", "1, 2,3").unwrap(), Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(colour("--color", "#ff0080").unwrap(), [1.0, 0.0, 128.0 / 255.0]);
        assert_eq!(scale("--scale", "2", 0.5, 4.0).unwrap(), Vec3::splat(2.0));
        assert_eq!(range("--scale", "1.5..3", 1.0, 4.0).unwrap(), (1.5, 3.0));
        let q = rotation("--rotate", "0,0,1,90").unwrap();
        assert!((q * Vec3::X - Vec3::Y).length() < 1e-6);
        assert!(point("--at", "1,2").unwrap_err().to_string().contains("--at \"1,2\""));
        assert!(colour("--color", "1,2,3").unwrap_err().to_string().contains("0..1"));
        assert!(scale("--scale", "1,0,1", 0.5, 4.0).unwrap_err().to_string().contains("each scale 0.5 to 4"));
        assert!(range("--scale", "3..1", 1.0, 4.0).unwrap_err().to_string().contains("range"));
        let huge = point("--at", "1e308,0,0").unwrap_err().to_string();
        assert!(huge.contains("1e308 is not a finite number"), "{huge}");
    }

    #[test]
    fn values_out_of_range_name_the_range() {
        assert_eq!(within("--count", 5, 1, 9).unwrap(), 5);
        let e = within("--count", 10_000_000, 1, 2000).unwrap_err().to_string();
        assert_eq!(e, "--count 10000000 is out of range; allowed: 1 to 2000");
        assert!(within("radius =", f32::NAN, 0.1, 9.0).unwrap_err().to_string().starts_with("radius = NaN"));
        assert!(falloff("--falloff", 0.5).unwrap_err().to_string().contains("under 0.5"));
        assert!(point("--at", "1e7,0,0").unwrap_err().to_string().contains("-1000000 to 1000000"));
        assert!(rotation("--rotate", "0,0,1,1e9").unwrap_err().to_string().contains("-360 to 360"));
        assert!(range("--scale", "0.5..1e9", 0.001, 1e4).unwrap_err().to_string().contains("0.001 to 10000"));
        assert!(numbers("--noise", "1,inf", &[2]).is_err() && numbers("--noise", "nan,1", &[2]).is_err());
    }
}
