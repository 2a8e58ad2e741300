//! The root-finder study views (`roots`, `path`, `iterations`, `conditioning`) on the shipped
//! scenes: every pixel is a colour of the view's legend (at one sample a pixel, so nothing
//! is blended), and each view shows the real mix of the solver's cases where the paper says
//! they are (the heart's equator, the typed surfaces' singular points).

use kardia::pipeline::{Control, RenderRequest, Renderer, View};
use kardia::scene::{self, LoadOptions};
use std::collections::BTreeMap;

/// Pixels of `view` of the scene file per 8-bit sRGB colour (`#rrggbb`), at 96×72, 1 spp.
fn census(file: &str, view: View) -> BTreeMap<String, usize> {
    let path = format!("{}/scenes/{file}", env!("CARGO_MANIFEST_DIR"));
    let scene = scene::parse_file(std::path::Path::new(&path), &LoadOptions::default()).unwrap();
    let request = RenderRequest {
        width: Some(96),
        height: Some(72),
        spp: 1,
        view,
        ..RenderRequest::default()
    };
    let image = Renderer::new(2)
        .unwrap()
        .render(&scene, &request, &Control::default())
        .unwrap()
        .image;
    let mut counts = BTreeMap::new();
    for px in image.to_srgb8().chunks(3) {
        let key = format!("#{:02x}{:02x}{:02x}", px[0], px[1], px[2]);
        *counts.entry(key).or_insert(0) += 1;
    }
    counts
}

/// The legend's colours of `view` by meaning, with black (no root finder reached).
fn legend(view: View) -> BTreeMap<String, String> {
    let mut out: BTreeMap<String, String> = view
        .legend()
        .unwrap()
        .swatches
        .into_iter()
        .map(|s| {
            let [r, g, b] = s.srgb;
            (format!("#{r:02x}{g:02x}{b:02x}"), s.label)
        })
        .collect();
    out.insert("#000000".into(), "nothing".into());
    out
}

/// The path view's colour of a miss settled as `hex` (40 % of each 8-bit value).
fn darker(hex: &str) -> String {
    let v: Vec<u16> = (0..3)
        .map(|i| u16::from_str_radix(&hex[1 + 2 * i..3 + 2 * i], 16).unwrap())
        .collect();
    format!(
        "#{:02x}{:02x}{:02x}",
        v[0] * 40 / 100,
        v[1] * 40 / 100,
        v[2] * 40 / 100
    )
}

/// `counts` by legend meaning; panics on a colour the legend does not have.
fn by_meaning(view: View, counts: &BTreeMap<String, usize>, file: &str) -> BTreeMap<String, usize> {
    let mut legend = legend(view);
    if view == View::Path {
        let misses: Vec<_> = legend
            .iter()
            .filter(|(k, _)| *k != "#000000")
            .map(|(k, v)| (darker(k), format!("{v} (miss)")))
            .collect();
        legend.extend(misses);
    }
    let mut out = BTreeMap::new();
    for (colour, n) in counts {
        let meaning = legend
            .get(colour)
            .unwrap_or_else(|| panic!("{file}, {view}: colour {colour} is not in the legend"));
        *out.entry(meaning.clone()).or_insert(0) += n;
    }
    out
}

const SCENES: [&str; 9] = [
    "heart.scene",
    "heart_equator.scene",
    "implicit/barth_sextic.scene",
    "implicit/chmutov.scene",
    "implicit/clebsch.scene",
    "implicit/kummer.scene",
    "implicit/sphere16.scene",
    "implicit/taubin_heart.scene",
    "implicit/torus.scene",
];

#[test]
fn every_pixel_of_every_solver_view_is_a_legend_colour() {
    for file in SCENES {
        for view in [
            View::Roots,
            View::Path,
            View::Iterations,
            View::Conditioning,
        ] {
            let counts = by_meaning(view, &census(file, view), file);
            eprintln!("{file} {view}: {counts:?}");
            assert!(
                counts.len() >= 2,
                "{file} {view}: one colour only: {counts:?}"
            );
        }
    }
}

/// Pixels of `view` of `file` with the legend meaning `meaning`.
fn pixels(file: &str, view: View, meaning: &str) -> usize {
    by_meaning(view, &census(file, view), file)
        .get(meaning)
        .copied()
        .unwrap_or(0)
}

#[test]
fn the_solver_views_show_each_surface_s_own_hard_cases() {
    // The heart: two roots through the body, four through both lobes; the Bernstein test
    // settles nearly all rays, the zero-region subdivision the few at the equator's triple
    // root, where |∇f| vanishes.
    let heart = "heart.scene";
    assert!(pixels(heart, View::Roots, "2 roots") > 2000);
    assert!(pixels(heart, View::Roots, "4 roots") > 0);
    assert!(pixels(heart, View::Path, "Bernstein test") > 2000);
    // Rays that pass beside the heart but through its bounding ellipsoids are proved to miss
    // (those beside the ellipsoids never reach the solver: black).
    assert!(pixels(heart, View::Path, "Bernstein test (miss)") > 300);
    assert!(pixels(heart, View::Path, "multiple-root subdivision") > 0);
    assert!(pixels(heart, View::Conditioning, "below 1e-6") > 0);
    assert!(
        pixels(heart, View::Iterations, "0") > 300,
        "proved misses refine nothing"
    );
    // Taubin's heart is the paper's heart stretched, with x and y swapped: it takes the
    // heart's path, whose subdivision settles its equator curve as the heart's.
    let taubin = "implicit/taubin_heart.scene";
    assert!(pixels(taubin, View::Path, "multiple-root subdivision") > 0);
    assert_eq!(pixels(taubin, View::Path, "double-double re-solve"), 0);
    // Chmutov's octic: rays through three of its lobes.
    assert!(pixels("implicit/chmutov.scene", View::Roots, "6 roots") > 0);
    // The degree-16 sphere: in and out, never more.
    let sphere = by_meaning(
        View::Roots,
        &census("implicit/sphere16.scene", View::Roots),
        "",
    );
    assert_eq!(
        sphere.keys().collect::<Vec<_>>(),
        ["0 roots", "2 roots", "nothing"]
    );
}
