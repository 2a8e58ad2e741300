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
    let classic = |id, title, about, equation, scale, bound| GalleryPreset {
        preset: None,
        equation: Some(equation),
        ..entry(id, title, about, scale, bound)
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
        classic(
            "cayley",
            "Cayley's cubic",
            "Cayley's nodal cubic: four double points, the most a cubic surface can have, at the corners of a tetrahedron where its cones meet.",
            "4*(x^2 + y^2 + z^2) + 16*x*y*z - 1",
            0.9,
            1.6,
        ),
        classic(
            "roman",
            "Steiner's Roman surface",
            "Steiner's Roman surface: the real projective plane squeezed into space; three lines of self-intersection cross at the centre and end in six pinch points.",
            "x^2*y^2 + y^2*z^2 + z^2*x^2 - x*y*z",
            2.2,
            1.0,
        ),
        classic(
            "togliatti",
            "Togliatti quintic",
            "Togliatti's quintic with 31 nodes, the most a quintic can have (Beauville proved it): a cone of degree two and five planes, in five-fold symmetry.",
            concat!(
                "(1 - 0.831253875554907*z)*(x^2 + y^2 - 1 + 1.927050983124842*z^2)^2 - ",
                "3.849606112048293*(x - z)*(0.309016994374947*x + 0.951056516295154*y - ",
                "z)*(-0.809016994374947*x + 0.587785252292473*y - z)*(-0.809016994374948*x - ",
                "0.587785252292473*y - z)*(0.309016994374947*x - 0.951056516295154*y - z)",
            ),
            0.36,
            3.8,
        ),
        classic(
            "barth_decic",
            "Barth decic",
            "Barth's decic: 345 nodes, with the symmetries of the icosahedron and golden-ratio coefficients.",
            concat!(
                "8*(x^2 - 6.854101966249686*y^2)*(y^2 - 6.854101966249686*z^2)*(z^2 - ",
                "6.854101966249686*x^2)*(x^4 + y^4 + z^4 - 2*x^2*y^2 - 2*y^2*z^2 - 2*z^2*x^2) + ",
                "11.090169943749475*(x^2 + y^2 + z^2 - 1)^2*(x^2 + y^2 + z^2 - ",
                "0.381966011250105)^2",
            ),
            0.9,
            1.8,
        ),
        classic(
            "labs",
            "Labs septic",
            "Labs' septic with 99 nodes, the most known for degree seven; seven-fold symmetry, and a coefficient that is a root of a cubic.",
            concat!(
                "x*(x^6 - 21*x^4*y^2 + 35*x^2*y^4 - 7*y^6) + 7*z*((x^2 + y^2)^3 - 8*z^2*(x^2 + ",
                "y^2)^2 + 16*z^4*(x^2 + y^2)) - 64*z^7 - (z + 51.94261459481465)*((z + 1)*(x^2 + ",
                "y^2) - 0.078528201496985*z^3 - 4.158360592288017*z^2 - 4.147143488965512*z - ",
                "1.188165938071479)^2",
            ),
            0.2,
            7.0,
        ),
        classic(
            "endrass",
            "Endraß octic",
            "Endraß's octic: 168 nodes, the most known for degree eight, with the eight-fold symmetry of its four pairs of planes.",
            concat!(
                "64*(x^2 - 1)*(y^2 - 1)*((x + y)^2 - 2)*((x - y)^2 - 2) - (-4*(1 + ",
                "2*1.414213562373095)*(x^2 + y^2)^2 + 8*(2 + 3*1.414213562373095)*z^2*(x^2 + y^2) ",
                "+ 2*(2 + 7*1.414213562373095)*(x^2 + y^2) - 16*z^4 + 8*(1 - ",
                "2*1.414213562373095)*z^2 - (1 + 12*1.414213562373095))^2",
            ),
            0.34,
            3.6,
        ),
        classic(
            "sarti",
            "Sarti dodecic",
            "Sarti's dodecic: 600 nodes, the most known for degree twelve, built from invariants of a group of order 7200.",
            concat!(
                "243*(73.79024325749306*((x^2*y^2 + z^2)^2*(x^2*z^2 + y^2) - (x^2*y^2 + ",
                "z^2)*(x^2*z^2 + y^2)^2 + (x^2*z^2 + y^2)^2*(x^2 + y^2*z^2) - (x^2*z^2 + ",
                "y^2)*(x^2 + y^2*z^2)^2 + (x^2 + y^2*z^2)^2*(x^2*y^2 + z^2) - (x^2 + ",
                "y^2*z^2)*(x^2*y^2 + z^2)^2) + 19*((x^2*y^2 + z^2)^2*(x^2*z^2 + y^2) + (x^2*y^2 + ",
                "z^2)*(x^2*z^2 + y^2)^2 + (x^2*z^2 + y^2)^2*(x^2 + y^2*z^2) + (x^2*z^2 + ",
                "y^2)*(x^2 + y^2*z^2)^2 + (x^2 + y^2*z^2)^2*(x^2*y^2 + z^2) + (x^2 + ",
                "y^2*z^2)*(x^2*y^2 + z^2)^2) + 10*((x^2*y^2 + z^2)^3 + (x^2*z^2 + y^2)^3 + (x^2 + ",
                "y^2*z^2)^3) - 14*(x^4 + y^4 + z^4 + 1)*((x^2*y^2 + z^2)*(x^2*z^2 + y^2) + ",
                "(x^2*y^2 + z^2)*(x^2 + y^2*z^2) + (x^2*z^2 + y^2)*(x^2 + y^2*z^2)) + 2*(x^4 + ",
                "y^4 + z^4 + 1)^2*((x^2*y^2 + z^2) + (x^2*z^2 + y^2) + (x^2 + y^2*z^2)) - 6*(x^4 ",
                "+ y^4 + z^4 + 1)*((x^2*y^2 + z^2)^2 + (x^2*z^2 + y^2)^2 + (x^2 + y^2*z^2)^2) - ",
                "352*(x*y*z)^2*((x^2*y^2 + z^2) + (x^2*z^2 + y^2) + (x^2 + y^2*z^2)) + ",
                "336*(x*y*z)^2*(x^4 + y^4 + z^4 + 1) + 48*(x^2*y^2 + z^2)*(x^2*z^2 + y^2)*(x^2 + ",
                "y^2*z^2)) - 22*(x^2 + y^2 + z^2 + 1)^6",
            ),
            0.4,
            3.7,
        ),
        classic(
            "dingdong",
            "Ding-dong",
            "x² + y² = z²(1 − z): a cone with a ball on its tip, touching at one node.",
            "x^2 + y^2 + z^3 - z^2",
            0.8,
            1.6,
        ),
    ]
}

/// Camera of equation mode's default view, as the page writes it: eye, look-at, up,
/// horizontal field of view in degrees.
pub const DEFAULT_CAMERA: ([f64; 3], [f64; 3], [f64; 3], f64) =
    ([6.0, 1.2, 0.9], [0.0, 0.0, 0.05], [0.0, 0.0, 1.0], 32.0);

/// The equation-mode scene of `entry` at its default parameters, seen from
/// [`DEFAULT_CAMERA`] with the page's lights and default colours: what its gallery thumbnail
/// shows (`kardia render` of this text draws the same image).
pub fn scene_text(entry: &GalleryPreset) -> String {
    let surface = match (entry.preset, entry.equation) {
        (Some(name), _) => {
            let params: Vec<String> = entry.sliders.iter().map(|s| s.value.to_string()).collect();
            [name.to_string(), params.join(" ")]
                .join(" ")
                .trim()
                .to_string()
        }
        (None, Some(equation)) => format!("\"{equation}\""),
        (None, None) => "\"x^2 + y^2 + z^2 - 1\"".into(),
    };
    let (eye, look, up, fov) = DEFAULT_CAMERA;
    let v = |a: [f64; 3]| format!("({}, {}, {})", a[0], a[1], a[2]);
    let s = entry.scale;
    format!(
        "CAMERA {} {} {} {fov}\n\
         BACKGROUND (0.03, 0.03, 0.05)\n\
         AMBIENT (0.06, 0.06, 0.07)\n\
         LIGHT (7, -4, 6) (0.9, 0.88, 0.85) 0.6 SAMPLES 4\n\
         LIGHT (3, 6, 1) (0.25, 0.25, 0.3)\n\
         IMPLICIT {surface} (0, 0, 0) ({s}, 0, 0) (0, {s}, 0) (0, 0, {s}) \
         (0.7454, 0.0319, 0.0802) SPECULAR 0.4 60 INSIDE (0.8714, 0.6308, 0.117) BOUND {}\n",
        v(eye),
        v(look),
        v(up),
        entry.bound
    )
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

    #[test]
    fn every_gallery_scene_parses_and_its_surface_is_seen() {
        use crate::pipeline::{Control, RenderRequest, Renderer};
        let gallery = presets();
        assert!(gallery.iter().filter(|g| g.equation.is_some()).count() >= 9);
        let mut ids: Vec<_> = gallery.iter().map(|g| g.id).collect();
        ids.sort();
        ids.dedup();
        assert_eq!(ids.len(), gallery.len(), "ids are unique");
        let renderer = Renderer::new(1).unwrap();
        for g in &gallery {
            let text = scene_text(g);
            let scene = parse(&text, g.id, &LoadOptions::default())
                .unwrap_or_else(|e| panic!("{}: {e}", g.id));
            // The surface is in the frame: a small render hits it on a good part of the
            // image and leaves the corners to the background.
            let request = RenderRequest {
                width: Some(40),
                height: Some(30),
                spp: 1,
                view: crate::pipeline::View::Depth,
                ..RenderRequest::default()
            };
            let image = renderer
                .render(&scene, &request, &Control::default())
                .unwrap()
                .image;
            let background = image.pixels[0];
            let covered = image.pixels.iter().filter(|p| **p != background).count();
            let fraction = covered as f64 / image.pixels.len() as f64;
            assert!(
                (0.08..0.95).contains(&fraction),
                "{}: the surface covers {fraction} of the thumbnail",
                g.id
            );
        }
    }
}
