//! Small value parsers for command-line options and manifest fields; every error names
//! the option or field and the value.

use crate::error::{Error, Result};
use glam::{Quat, Vec3};

/// Comma-separated numbers, exactly `n` of them (or any of `ns`).
pub fn numbers(option: &str, text: &str, ns: &[usize]) -> Result<Vec<f32>> {
    let values: std::result::Result<Vec<f32>, _> = text.split(',').map(|s| s.trim().parse::<f32>()).collect();
    match values {
        Ok(v) if ns.contains(&v.len()) && v.iter().all(|x| x.is_finite()) => Ok(v),
        _ => Err(Error::invalid(format!(
            "{option} {text:?} is not {} comma-separated numbers",
            ns.iter().map(|n| n.to_string()).collect::<Vec<_>>().join(" or ")
        ))),
    }
}

/// `X,Y,Z`.
pub fn point(option: &str, text: &str) -> Result<Vec3> {
    let v = numbers(option, text, &[3])?;
    Ok(Vec3::new(v[0], v[1], v[2]))
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

/// `AX,AY,AZ,DEG`: a rotation of DEG degrees about the axis (AX, AY, AZ).
pub fn rotation(option: &str, text: &str) -> Result<Quat> {
    let v = numbers(option, text, &[4])?;
    let axis = Vec3::new(v[0], v[1], v[2]);
    let axis =
        axis.try_normalize().ok_or_else(|| Error::invalid(format!("{option} {text:?}: the axis has zero length")))?;
    Ok(Quat::from_axis_angle(axis, v[3].to_radians()))
}

/// `S` or `SX,SY,SZ`, all positive.
pub fn scale(option: &str, text: &str) -> Result<Vec3> {
    let v = numbers(option, text, &[1, 3])?;
    let s = if v.len() == 1 { Vec3::splat(v[0]) } else { Vec3::new(v[0], v[1], v[2]) };
    if s.min_element() <= 0.0 {
        return Err(Error::invalid(format!("{option} {text:?}: scales must be positive")));
    }
    Ok(s)
}

/// `MIN..MAX` (or a single number).
pub fn range(option: &str, text: &str) -> Result<(f32, f32)> {
    let parts: Vec<&str> = text.split("..").collect();
    let bad = || Error::invalid(format!("{option} {text:?} is not a range like 1.5..3"));
    let nums: Vec<f32> = parts.iter().map(|p| p.trim().parse::<f32>().map_err(|_| bad())).collect::<Result<_>>()?;
    match nums.as_slice() {
        [a] => Ok((*a, *a)),
        [a, b] if a <= b => Ok((*a, *b)),
        _ => Err(bad()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_names_the_option() {
        assert_eq!(point("--at", "1, 2,3").unwrap(), Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(colour("--color", "#ff0080").unwrap(), [1.0, 0.0, 128.0 / 255.0]);
        assert_eq!(scale("--scale", "2").unwrap(), Vec3::splat(2.0));
        assert_eq!(range("--scale", "1.5..3").unwrap(), (1.5, 3.0));
        let q = rotation("--rotate", "0,0,1,90").unwrap();
        assert!((q * Vec3::X - Vec3::Y).length() < 1e-6);
        assert!(point("--at", "1,2").unwrap_err().to_string().contains("--at \"1,2\""));
        assert!(colour("--color", "1,2,3").unwrap_err().to_string().contains("0..1"));
        assert!(scale("--scale", "1,0,1").unwrap_err().to_string().contains("positive"));
        assert!(range("--scale", "3..1").unwrap_err().to_string().contains("range"));
    }
}
