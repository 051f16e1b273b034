//! Classification on a generated set of volumes of known type, under axis permutations.

use glam::Vec3;
use solidtex::TextureType;
use solidtex::classify::classify;
use solidtex::noise::fbm;
use solidtex::volume::{Axis, Channel, Volume};

const SIDE: usize = 24;

/// Isotropic noise solid.
fn isotropic(seed: u64) -> Volume {
    Volume::from_fn([SIDE; 3], Channel::grey(), |x, y, z, o| {
        let p = Vec3::new(x as f32, y as f32, z as f32) / 6.0;
        o[0] = 0.5 + 0.4 * fbm(seed, p, [4; 3], 3);
    })
    .unwrap()
}

/// Fibres along x: a 2D noise cross-section swept along x, with a little noise along x.
fn fibres(seed: u64) -> Volume {
    Volume::from_fn([SIDE; 3], Channel::rgb(), |x, y, z, o| {
        let p = Vec3::new(0.0, y as f32 / 4.0, z as f32 / 4.0);
        let v = 0.5
            + 0.4 * fbm(seed, p, [1, 6, 6], 3)
            + 0.03 * fbm(seed ^ 1, Vec3::new(x as f32, y as f32, z as f32) / 8.0, [3; 3], 2);
        o.copy_from_slice(&[v, v * 0.8, v * 0.6]);
    })
    .unwrap()
}

/// Strata stacked along z: bands that change with z, a little noise within the slices.
fn strata(seed: u64) -> Volume {
    Volume::from_fn([SIDE; 3], Channel::rgb(), |x, y, z, o| {
        let band = 0.5 + 0.4 * fbm(seed, Vec3::new(0.5, 0.5, z as f32 / 3.0), [1, 1, 8], 2);
        let grain = 0.04 * fbm(seed ^ 2, Vec3::new(x as f32, y as f32, z as f32) / 4.0, [6; 3], 2);
        o.copy_from_slice(&[band + grain, band * 0.9 + grain, band * 0.7]);
    })
    .unwrap()
}

const ORDERS: [[Axis; 3]; 6] = [
    [Axis::X, Axis::Y, Axis::Z],
    [Axis::X, Axis::Z, Axis::Y],
    [Axis::Y, Axis::X, Axis::Z],
    [Axis::Y, Axis::Z, Axis::X],
    [Axis::Z, Axis::X, Axis::Y],
    [Axis::Z, Axis::Y, Axis::X],
];

/// Where the old axis `old` went under `order`.
fn moved(order: [Axis; 3], old: Axis) -> String {
    Axis::ALL[order.iter().position(|a| *a == old).unwrap()].to_string()
}

#[test]
fn classification_is_right_on_at_least_95_percent_of_the_generated_set() {
    let mut right = 0;
    let mut total = 0;
    let mut misses = Vec::new();
    for seed in 1..=3u64 {
        let cases: [(&str, Volume, TextureType, Option<Axis>); 3] = [
            ("isotropic", isotropic(seed), TextureType::T0, None),
            ("fibres", fibres(seed), TextureType::T1a, Some(Axis::X)),
            ("strata", strata(seed), TextureType::T1b, Some(Axis::Z)),
        ];
        for (name, volume, want, axis) in &cases {
            for order in ORDERS {
                let c = classify(&volume.permuted(order).unwrap()).unwrap();
                let axis_ok = match (want, axis) {
                    (TextureType::T1b, Some(a)) => c.depth_axis == Some(moved(order, *a)),
                    (_, Some(a)) => c.primary_axis == Some(moved(order, *a)),
                    _ => true,
                };
                total += 1;
                if c.texture_type == *want && axis_ok {
                    right += 1;
                } else {
                    misses.push(format!("{name} seed {seed} order {order:?}: {c:?}"));
                }
            }
        }
    }
    let share = right as f64 / total as f64;
    eprintln!("classification: {right}/{total} right");
    assert!(share >= 0.95, "{right}/{total} right; misses:\n{}", misses.join("\n"));
}

#[test]
fn a_permuted_volume_reports_the_permuted_axes() {
    let v = strata(4);
    assert_eq!(classify(&v).unwrap().depth_axis.as_deref(), Some("z"));
    let turned = v.permuted([Axis::Z, Axis::X, Axis::Y]).unwrap();
    assert_eq!(classify(&turned).unwrap().depth_axis.as_deref(), Some("x"));
    let f = fibres(4).permuted([Axis::Y, Axis::X, Axis::Z]).unwrap();
    let c = classify(&f).unwrap();
    assert_eq!((c.texture_type, c.primary_axis.as_deref()), (TextureType::T1a, Some("y")));
}
