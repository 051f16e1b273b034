//! Classification on the labelled set (tests/it/labelled.rs) under all six axis orders:
//! the share right, type and axis, per type; what the confidence means; permuted axes.

use crate::labelled::{Case, cases};
use solidtex::TextureType;
use solidtex::classify::{Classification, classify};
use solidtex::volume::Axis;

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

/// Type right, and the axis the type names (1-a: primary; 1-b, 2-b: depth) where it went.
fn right(case: &Case, order: [Axis; 3], c: &Classification) -> bool {
    let axis_ok = match (case.want, case.axis) {
        (TextureType::T1b | TextureType::T2b, Some(a)) => c.depth_axis == Some(moved(order, a)),
        (_, Some(a)) => c.primary_axis == Some(moved(order, a)),
        _ => true,
    };
    c.texture_type == case.want && axis_ok
}

#[test]
fn classification_is_right_on_at_least_95_percent_of_the_labelled_set() {
    let set = cases();
    assert!(set.len() >= 100, "{} solids", set.len());
    let mut results = Vec::new();
    let mut misses = Vec::new();
    for case in &set {
        for order in ORDERS {
            let c = classify(&case.volume.permuted(order).unwrap()).unwrap();
            let ok = right(case, order, &c);
            if !ok {
                misses.push(format!("{} ({}) {order:?}: {c:?}", case.name, case.why));
            }
            results.push((case.want, c.confidence, ok));
        }
    }
    let share = |keep: &dyn Fn(&(TextureType, f64, bool)) -> bool| {
        let kept: Vec<_> = results.iter().filter(|r| keep(r)).collect();
        (kept.iter().filter(|r| r.2).count(), kept.len())
    };
    for t in [TextureType::T0, TextureType::T1a, TextureType::T1b, TextureType::T2a, TextureType::T2b] {
        let (n, of) = share(&|r| r.0 == t);
        eprintln!("type {t}: {n}/{of} right");
        assert!(n * 100 >= of * 85, "type {t}: {n}/{of} right; misses:\n{}", misses.join("\n"));
    }
    for floor in [0.0, 0.3, 0.5, 0.7, 0.9] {
        let (n, of) = share(&|r| r.1 >= floor);
        eprintln!("confidence >= {floor}: {n}/{of} right");
    }
    let (n, of) = share(&|_| true);
    eprintln!("classification: {n}/{of} right ({} solids x 6 axis orders)", set.len());
    assert!(n * 100 >= of * 95, "{n}/{of} right; misses:\n{}", misses.join("\n"));
    // A confident estimate is right: above 0.7 at most one in a hundred is wrong.
    let (n, of) = share(&|r| r.1 >= 0.7);
    assert!(of > results.len() / 2 && n * 100 >= of * 99, "{n}/{of} right at confidence >= 0.7");
}

#[test]
fn a_permuted_volume_reports_the_permuted_axes() {
    let set = cases();
    let find = |name: &str| set.iter().find(|c| c.name == name).unwrap();
    let kiwi = &find("kiwi sweep, no skin 1").volume;
    let c = classify(kiwi).unwrap();
    assert_eq!(
        (c.texture_type, c.depth_axis.as_deref(), c.primary_axis.as_deref()),
        (TextureType::T2b, Some("z"), Some("x"))
    );
    let turned = classify(&kiwi.permuted([Axis::Z, Axis::X, Axis::Y]).unwrap()).unwrap();
    assert_eq!((turned.depth_axis.as_deref(), turned.primary_axis.as_deref()), (Some("x"), Some("y")));
    let fibres = find("thin clean fibres 1").volume.permuted([Axis::Y, Axis::X, Axis::Z]).unwrap();
    let c = classify(&fibres).unwrap();
    assert_eq!((c.texture_type, c.primary_axis.as_deref()), (TextureType::T1a, Some("y")));
}

#[test]
fn the_scores_rank_every_type_and_the_estimate_first() {
    for case in cases().iter().step_by(7) {
        let c = classify(&case.volume).unwrap();
        assert_eq!(c.nearest.len(), 7, "{}", case.name);
        assert!((c.nearest.iter().map(|n| n.score).sum::<f64>() - 1.0).abs() < 1e-9, "{}", case.name);
        assert_eq!(c.nearest[0].texture_type, c.texture_type, "{}: {c:?}", case.name);
        assert_eq!(c.confidence, c.nearest[0].score, "{}", case.name);
    }
}
