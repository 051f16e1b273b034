//! Sketch-guided solid texturing: the frame field and its picture.

use crate::support::{at, solidtex, stderr};

/// `solidtex field` draws the kiwi spec's field on the cut through the fruit's axis: inside,
/// the frames' x axis follows the stroke along the fruit (red: x in model space), outside
/// is black; a spec without strokes is refused by name.
#[test]
fn the_field_of_a_kiwi_spec_follows_its_stroke_on_a_cut() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (fruit, spec) = crate::fill::kiwi_fruit(d);
    let png = at(d, "field.png");
    let run = solidtex(&["field", &fruit, "--spec", &spec, "--size", "96", "--plane", "0,0,0,0,0,1", "-o", &png]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(stderr(&run).contains("sketched frames; the field solved in"), "{}", stderr(&run));
    let img = image::open(&png).unwrap().to_rgb8();
    assert_eq!(img.get_pixel(1, 1).0, [0, 0, 0], "outside the fruit");
    let mut red = 0;
    for x in 30..66 {
        let [r, g, b] = img.get_pixel(x, 48).0;
        if r > g && r > b {
            red += 1;
        }
    }
    assert!(red >= 30, "{red} of 36 pixels along the axis show x as red");

    let bare = crate::fill::spec(d, "bare.toml", "exemplar = \"kiwi\"\n");
    let run = solidtex(&["field", &fruit, "--spec", &bare, "-o", &at(d, "bare.png")]);
    assert!(!run.status.success());
    assert!(stderr(&run).contains("bare.toml") && stderr(&run).contains("direction stroke"), "{}", stderr(&run));
    assert!(!d.join("bare.png").exists());
}
