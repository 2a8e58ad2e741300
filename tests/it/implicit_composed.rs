//! Equations `a·Pⁿ + c` (a power of one sub-expression shifted by a constant) are traced as
//! the union of their level sets `P = r`, `r` the real roots of `a·sⁿ + c`: the same hits,
//! normals and pictures as those level sets written out as separate surfaces (each signed so
//! that its outward side is `f`'s), and the root finder sees `P`'s low degree, not `n·deg P`.

use crate::render_support::{pixels, render, RenderSettings};

use kardia::camera::Camera;
use kardia::geometry::{DVec3, Frame, Ray};
use kardia::scene::{parse, LoadOptions};
use kardia::shapes::implicit::Implicit;
use kardia::shapes::report::SettledBy;
use kardia::shapes::Shape;

/// Clip radius of every surface here.
const BOUND: f64 = 2.0;

/// A composition and its level sets as the test writes them out by hand.
struct Case {
    /// The equation as typed.
    equation: &'static str,
    /// `P`.
    inner: &'static str,
    /// `a` and `q = −c/a` of `a·Pⁿ + c`, and `n`.
    scale: f64,
    q: f64,
    power: i32,
}

const CASES: [Case; 6] = [
    Case {
        equation: "(x^2+y^2-1)^8 - 1e-12",
        inner: "x^2+y^2-1",
        scale: 1.0,
        q: 1e-12,
        power: 8,
    },
    Case {
        equation: "(x+y+z+1)^16 - 1",
        inner: "x+y+z+1",
        scale: 1.0,
        q: 1.0,
        power: 16,
    },
    Case {
        equation: "(x^2+y^2+z^2-1)^8 - 1e-5",
        inner: "x^2+y^2+z^2-1",
        scale: 1.0,
        q: 1e-5,
        power: 8,
    },
    Case {
        equation: "((x-0.5)^2+(y+0.3)^2+(z-0.2)^2)^8 = 1",
        inner: "(x-0.5)^2+(y+0.3)^2+(z-0.2)^2",
        scale: 1.0,
        q: 1.0,
        power: 8,
    },
    // An odd power with a negative factor: one level, where h′ < 0.
    Case {
        equation: "1 - 2*(x+y-z)^3",
        inner: "x+y-z",
        scale: -2.0,
        q: 0.5,
        power: 3,
    },
    // A negative factor and an even power: h′ < 0 at the positive root, > 0 at the other.
    Case {
        equation: "0.01 - (x^2+y^2+z^2-1)^4",
        inner: "x^2+y^2+z^2-1",
        scale: -1.0,
        q: 0.01,
        power: 4,
    },
];

impl Case {
    /// Each level set `P = r` as an equation whose outward side is `f`'s: `P − r` where
    /// `h′(r) = a·n·rⁿ⁻¹ > 0`, else `r − P`.
    fn levels(&self) -> Vec<String> {
        let r = self.q.abs().powf(1.0 / self.power as f64);
        let roots = if self.power % 2 == 0 {
            vec![-r, r]
        } else {
            vec![r.copysign(self.q)]
        };
        roots
            .into_iter()
            .map(|r: f64| {
                let slope = self.scale * r.powi(self.power - 1);
                if slope > 0.0 {
                    format!("({}) - ({r:e})", self.inner)
                } else {
                    format!("({r:e}) - ({})", self.inner)
                }
            })
            .collect()
    }
}

/// The explorer's default view (as `bench/cliffs.sh` renders it).
fn camera() -> Camera {
    Camera::new(
        DVec3::new(6.0, 1.2, 0.9),
        DVec3::new(0.0, 0.0, 0.05),
        DVec3::Z,
        32.0,
    )
    .unwrap()
}

/// The camera rays of an `n × n` grid.
fn rays(n: u32) -> Vec<Ray> {
    let cam = camera();
    (0..n * n)
        .map(|i| cam.ray((i % n) as f64 + 0.5, (i / n) as f64 + 0.5, n, n))
        .collect()
}

/// Every camera ray meets a composition where it meets the nearest of its level sets, to
/// 1e-12 of the distance, with the same outward normal to 1e-12 (its sign included).
#[test]
fn a_composition_is_hit_where_its_level_sets_are_with_their_normals() {
    for case in CASES {
        let shape = Implicit::new(case.equation, Frame::identity(), Some(BOUND)).unwrap();
        let levels: Vec<Implicit> = case
            .levels()
            .iter()
            .map(|text| Implicit::new(text, Frame::identity(), Some(BOUND)).unwrap())
            .collect();
        let mut hits = 0;
        for ray in rays(48) {
            let got = shape.intersect(&ray, 1e-9, f64::INFINITY);
            let want = levels
                .iter()
                .filter_map(|l| Some((l.intersect(&ray, 1e-9, f64::INFINITY)?, l)))
                .min_by(|a, b| a.0.total_cmp(&b.0));
            match (got, want) {
                (None, None) => {}
                (Some(t), Some((w, level))) => {
                    hits += 1;
                    assert!(
                        (t - w).abs() <= 1e-12 * w,
                        "{}: {ray:?} at {t}, its level set at {w}",
                        case.equation
                    );
                    let n = shape.normal(ray.at(t));
                    let m = level.normal(ray.at(w));
                    assert!(
                        (n - m).length() <= 1e-12,
                        "{}: normal {n} at {}, its level set's {m}",
                        case.equation,
                        ray.at(t)
                    );
                }
                _ => panic!(
                    "{}: {ray:?} gives {got:?}, its level sets {want:?}",
                    case.equation
                ),
            }
        }
        assert!(hits > 200, "{}: only {hits} hits", case.equation);
    }
}

/// The scene `bench/cliffs.sh` renders, with each of `equations` as a surface.
fn scene_text(equations: &[String]) -> String {
    let mut text = String::from(
        "CAMERA (6, 1.2, 0.9) (0, 0, 0.05) (0, 0, 1) 32\n\
         BACKGROUND (0.03, 0.03, 0.05)\n\
         AMBIENT (0.06, 0.06, 0.07)\n\
         LIGHT (7, -4, 6) (0.9, 0.88, 0.85) 0.6 SAMPLES 4\n\
         LIGHT (3, 6, 1) (0.25, 0.25, 0.3)\n",
    );
    for e in equations {
        text += &format!(
            "IMPLICIT \"{e}\" (0, 0, 0) (1, 0, 0) (0, 1, 0) (0, 0, 1) (0.7454, 0.0319, 0.0802) \
             SPECULAR 0.4 60 INSIDE (0.8714, 0.6308, 0.117) BOUND {BOUND}\n"
        );
    }
    text
}

/// The picture of a composition (shadows, highlights, its inside colour where a ray sees
/// the inside) is the picture of its level sets as separate surfaces, to a pixel or two on
/// silhouettes.
#[test]
fn a_composition_renders_as_its_level_sets() {
    let settings = RenderSettings {
        spp: 1,
        max_depth: 4,
        seed: 7,
        threads: 1,
    };
    let options = LoadOptions::default();
    for case in &CASES[..4] {
        let mut whole =
            parse(&scene_text(&[case.equation.to_string()]), "whole", &options).unwrap();
        let mut parts = parse(&scene_text(&case.levels()), "levels", &options).unwrap();
        for scene in [&mut whole, &mut parts] {
            (scene.width, scene.height) = (64, 64);
        }
        let (a, b) = (
            pixels(&render(&whole, &settings)),
            pixels(&render(&parts, &settings)),
        );
        let differing = a
            .iter()
            .zip(&b)
            .filter(|(p, q)| p.iter().zip(q.iter()).any(|(u, v)| u.abs_diff(*v) > 2))
            .count();
        let lit = a.iter().filter(|p| p[0] > 40).count();
        assert!(
            lit > 200,
            "{}: the surface covers {lit} pixels",
            case.equation
        );
        assert!(
            differing <= 2,
            "{}: {differing} pixels differ",
            case.equation
        );
    }
}

/// The root finder sees the level sets' polynomials (`P`'s degree along the ray, simple
/// roots), never the expansion's degree-16 polynomial and its clusters of near-roots: what
/// the study views (`kardia probe`'s solver report, the solver view) show for such a surface.
#[test]
fn the_solver_sees_the_level_sets_not_the_clusters() {
    for (equation, degree) in [
        ("(x^2+y^2-1)^8 - 1e-12", 2),
        ("(x+y+z+1)^16 - 1", 1),
        ("(x^2+y^2+z^2-1)^8 - 1e-5", 2),
    ] {
        let shape = Implicit::new(equation, Frame::identity(), Some(BOUND)).unwrap();
        let mut hits = 0;
        for ray in rays(24) {
            let Some(report) = shape.solver_report(&ray, 1e-9, f64::INFINITY) else {
                continue;
            };
            assert_eq!(report.degree, degree, "{equation}: {ray:?}");
            assert_ne!(
                report.settled_by,
                SettledBy::Recentred,
                "{equation}: {ray:?}"
            );
            if report.hit.is_some() {
                hits += 1;
                assert_eq!(
                    report.hit,
                    shape.intersect(&ray, 1e-9, f64::INFINITY),
                    "{equation}: {ray:?}"
                );
            }
        }
        assert!(hits > 50, "{equation}: {hits}");
    }
}
