//! What the page offers to open: the surface presets of equation mode (each with one line of
//! text and its sliders) and the scene files of `scenes/`, embedded in the binary so that no
//! message ever names a server path.

use serde::Serialize;

/// A slider of a preset parameter.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Slider {
    /// Label on the page.
    pub label: &'static str,
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
    /// Step between values.
    pub step: f64,
    /// Value when the preset is chosen.
    pub value: f64,
}

/// One surface of the equation-mode gallery.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct GalleryPreset {
    /// Identifier on the page (a scene-language preset name, or `sphere16`).
    pub id: &'static str,
    /// Title on the page.
    pub title: &'static str,
    /// One line about the surface.
    pub about: &'static str,
    /// The scene-language preset it is written as (`IMPLICIT name params…`); `None` for a
    /// surface written as a quoted equation.
    pub preset: Option<&'static str>,
    /// The equation for surfaces without a preset.
    pub equation: Option<&'static str>,
    /// Its parameters' sliders, in the preset's order.
    pub sliders: Vec<Slider>,
    /// Object-space scale of the placed surface (world = scale · object), so that it fills
    /// the default view.
    pub scale: f64,
    /// Default clip radius (object space).
    pub bound: f64,
}

/// The equation-mode gallery, in the order shown.
pub fn presets() -> Vec<GalleryPreset> {
    let slider = |label, min, max, step, value| Slider {
        label,
        min,
        max,
        step,
        value,
    };
    let entry = |id, title, about, scale, bound| GalleryPreset {
        id,
        title,
        about,
        preset: Some(id),
        equation: None,
        sliders: vec![],
        scale,
        bound,
    };
    vec![
        entry(
            "heart",
            "Heart",
            "The paper's sextic heart (2x²+y²+z²−1)³ − (0.1x²+y²)z³ = 0, traced by HEART itself.",
            1.0,
            2.0,
        ),
        entry(
            "taubin_heart",
            "Taubin's heart",
            "Taubin's sextic heart, thin along y, through the generic implicit path.",
            1.0,
            2.0,
        ),
        GalleryPreset {
            sliders: vec![
                slider("R (ring radius)", 0.1, 2.0, 0.01, 1.0),
                slider("r (tube radius)", 0.02, 1.5, 0.01, 0.3),
            ],
            ..entry(
                "torus",
                "Torus",
                "A quartic ring: the tube of radius r about a circle of radius R.",
                1.0,
                1.365,
            )
        },
        GalleryPreset {
            sliders: vec![slider("μ", 0.2, 1.7, 0.005, 1.140175425)],
            ..entry(
                "kummer",
                "Kummer quartic",
                "Kummer's family of quartics; at μ² = 1.3 it has 16 real nodes.",
                0.5,
                2.28035085,
            )
        },
        entry(
            "barth_sextic",
            "Barth sextic",
            "Barth's sextic: 65 nodes, the most a sextic can have, 50 of them finite.",
            0.55,
            2.0,
        ),
        entry(
            "clebsch",
            "Clebsch cubic",
            "The Clebsch diagonal cubic, which holds all 27 of its lines as real lines.",
            0.25,
            5.0,
        ),
        GalleryPreset {
            sliders: vec![slider("n (degree)", 1.0, 16.0, 1.0, 6.0)],
            ..entry(
                "chmutov",
                "Chmutov surface",
                "T_n(x) + T_n(y) + T_n(z) = 0 with Chebyshev's T_n: many nodes for its degree n.",
                0.6,
                1.792,
            )
        },
        GalleryPreset {
            preset: None,
            equation: Some("(x^2+y^2+z^2)^8 = 1"),
            ..entry(
                "sphere16",
                "Degree-16 sphere",
                "(x²+y²+z²)⁸ = 1: a plain unit sphere, but every ray's polynomial has degree 16.",
                1.0,
                1.5,
            )
        },
    ]
}

/// The scene files of `scenes/`, as `(name, text)`, embedded at build time.
pub const SCENES: &[(&str, &str)] = &[
    ("heart.scene", include_str!("../../scenes/heart.scene")),
    (
        "heart_equator.scene",
        include_str!("../../scenes/heart_equator.scene"),
    ),
    (
        "glass_heart.scene",
        include_str!("../../scenes/glass_heart.scene"),
    ),
    ("hearts.scene", include_str!("../../scenes/hearts.scene")),
    (
        "heartbeat.scene",
        include_str!("../../scenes/heartbeat.scene"),
    ),
    (
        "turntable.scene",
        include_str!("../../scenes/turntable.scene"),
    ),
    (
        "menagerie.scene",
        include_str!("../../scenes/menagerie.scene"),
    ),
    (
        "implicit/barth_sextic.scene",
        include_str!("../../scenes/implicit/barth_sextic.scene"),
    ),
    (
        "implicit/chmutov.scene",
        include_str!("../../scenes/implicit/chmutov.scene"),
    ),
    (
        "implicit/clebsch.scene",
        include_str!("../../scenes/implicit/clebsch.scene"),
    ),
    (
        "implicit/kummer_morph.scene",
        include_str!("../../scenes/implicit/kummer_morph.scene"),
    ),
    (
        "implicit/kummer.scene",
        include_str!("../../scenes/implicit/kummer.scene"),
    ),
    (
        "implicit/sphere16.scene",
        include_str!("../../scenes/implicit/sphere16.scene"),
    ),
    (
        "implicit/taubin_heart.scene",
        include_str!("../../scenes/implicit/taubin_heart.scene"),
    ),
    (
        "implicit/torus.scene",
        include_str!("../../scenes/implicit/torus.scene"),
    ),
];

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{parse, LoadOptions};
    use crate::shapes::implicit::{preset, PRESETS};

    #[test]
    fn every_scene_file_is_embedded_and_parses() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
        let mut on_disk = vec![];
        for dir in [root.clone(), root.join("implicit")] {
            for entry in std::fs::read_dir(&dir).unwrap() {
                let path = entry.unwrap().path();
                if path.extension().is_some_and(|e| e == "scene") {
                    let name = path.strip_prefix(&root).unwrap();
                    on_disk.push(name.to_string_lossy().replace('\\', "/"));
                }
            }
        }
        on_disk.sort();
        let mut embedded: Vec<String> = SCENES.iter().map(|(n, _)| n.to_string()).collect();
        embedded.sort();
        assert_eq!(embedded, on_disk, "SCENES must list every file of scenes/");
        for (name, text) in SCENES {
            parse(text, name, &LoadOptions::default()).unwrap();
        }
    }

    #[test]
    fn gallery_covers_every_preset_with_its_default_bound_and_slider_count() {
        let gallery = presets();
        for (name, count) in PRESETS {
            let g = gallery
                .iter()
                .find(|g| g.preset == Some(*name))
                .unwrap_or_else(|| panic!("{name} missing from the gallery"));
            assert_eq!(g.sliders.len(), *count, "{name}");
            let values: Vec<f64> = g.sliders.iter().map(|s| s.value).collect();
            let p = preset(name, &values).unwrap();
            assert!(
                (p.bound - g.bound).abs() < 1e-3,
                "{name}: {} vs {}",
                p.bound,
                g.bound
            );
            for s in &g.sliders {
                assert!(s.min <= s.value && s.value <= s.max && s.step > 0.0);
            }
        }
        assert!(gallery.iter().any(|g| g.equation.is_some()));
    }
}
