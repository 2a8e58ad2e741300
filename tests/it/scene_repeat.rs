//! Scenes of many objects: a grid written with REPEAT reads as the same grid written out line
//! by line, and a scene rendered through its object index gives the picture of its objects
//! asked one by one, bit for bit.

use crate::render_support::{render, RenderSettings};
use kardia::scene::{parse, LoadOptions, Scene};

const HEAD: &str = "SIZE 48 40
CAMERA (9, 2, 3) (0, 0, 0) (0, 0, 1) 45
BACKGROUND (0.1, 0.1, 0.2)
AMBIENT (0.1, 0.1, 0.1)
LIGHT (6, -5, 8) (1, 1, 1) 0.5 SAMPLES 2
MATERIAL shiny (0.8, 0.2, 0.1) SPECULAR 0.5 30 REFLECT 0.2
PLANE (0, 0, -1.6) (0, 0, 1) (0.7, 0.7, 0.7) CHECKER (0.2, 0.2, 0.2) 0.5
";

/// A 4 × 5 grid of hearts (shiny) with a sphere beside each, written with REPEAT.
fn with_loops() -> String {
    format!(
        "{HEAD}REPEAT i FROM 0 TO 3
  REPEAT j FROM -2 TO 2
    LET s = 0.25 + 0.05 * i
    HEART (i - 1.5, j, 0.3 * j) (s, 0, 0) (0, s, 0) (0, 0, s) shiny
    SPHERE (i - 1.5, j + 0.4, -1) 0.15 (0.2, 0.6, 0.9) TRANSMIT 0.5 IOR 1.3
  END
END
"
    )
}

/// The same grid, each object on its own line.
fn written_out() -> String {
    let mut text = HEAD.to_string();
    for i in 0..4 {
        for j in -2..=2 {
            let s = 0.25 + 0.05 * f64::from(i);
            let x = f64::from(i) - 1.5;
            let (y, z) = (f64::from(j), 0.3 * f64::from(j));
            text += &format!("HEART ({x}, {y}, {z}) ({s}, 0, 0) (0, {s}, 0) (0, 0, {s}) shiny\n");
            let y = f64::from(j) + 0.4;
            text += &format!("SPHERE ({x}, {y}, -1) 0.15 (0.2, 0.6, 0.9) TRANSMIT 0.5 IOR 1.3\n");
        }
    }
    text
}

fn load(text: &str) -> Scene {
    parse(text, "grid.scene", &LoadOptions::default()).unwrap()
}

fn settings() -> RenderSettings {
    RenderSettings {
        spp: 2,
        max_depth: 4,
        seed: 3,
        threads: 2,
    }
}

#[test]
fn a_grid_written_with_repeat_renders_as_written_out() {
    let (looped, plain) = (load(&with_loops()), load(&written_out()));
    assert_eq!(looped.objects.len(), 41);
    assert!(looped.objects.len() >= Scene::INDEX_MIN_OBJECTS);
    let bounds = |s: &Scene| s.objects.iter().map(|o| o.bounds).collect::<Vec<_>>();
    assert_eq!(bounds(&looped), bounds(&plain));
    let settings = settings();
    assert_eq!(render(&looped, &settings), render(&plain, &settings));
}

#[test]
fn the_object_index_changes_no_pixel() {
    let indexed = load(&with_loops());
    let mut in_order = load(&with_loops());
    // Objects moved to a new vector are no longer those the index was built from: the
    // queries then ask every object in order.
    let objects = std::mem::take(&mut in_order.objects);
    let mut moved = Vec::with_capacity(objects.len() + 1);
    moved.extend(objects);
    in_order.objects = moved;
    let settings = settings();
    let (a, b) = (render(&indexed, &settings), render(&in_order, &settings));
    assert_eq!(a, b);
    // Something is seen: the test is not of an empty picture.
    let background = a.get(0, 0);
    assert!((0..a.height).any(|y| (0..a.width).any(|x| a.get(x, y) != background)));
}
