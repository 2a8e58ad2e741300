//! The equations of issue 36's cliffs (nearly multiple roots, expansions that cancel by many
//! orders): every camera ray of a grid hits them where their closed forms say — planes,
//! spheres and cylinders written as high powers — one ray at a time and four at once, with the
//! outward normal of the closed form. What `bench/cliffs.sh` times, checked for correctness.

use kardia::camera::Camera;
use kardia::geometry::{DVec3, Frame, Ray, LANES};
use kardia::shapes::implicit::Implicit;
use kardia::shapes::Shape;

/// Clip radius of every surface here.
const BOUND: f64 = 2.0;

/// Grid side of camera rays.
const N: u32 = 48;

/// Every parameter `t` where `ray` meets the zero set, by its closed form (in any order).
type Exact = fn(&Ray) -> Vec<f64>;

/// Roots of `a·t² + b·t + c` (a > 0), ascending.
fn quadratic(a: f64, b: f64, c: f64) -> Vec<f64> {
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return vec![];
    }
    let q = -0.5 * (b + b.signum() * disc.sqrt());
    let mut r = vec![q / a, c / q];
    r.sort_by(f64::total_cmp);
    r
}

/// Where the ray meets the sphere `|p − centre| = radius`.
fn sphere(ray: &Ray, centre: DVec3, radius: f64) -> Vec<f64> {
    let o = ray.origin - centre;
    quadratic(
        ray.dir.length_squared(),
        2.0 * o.dot(ray.dir),
        o.length_squared() - radius * radius,
    )
}

/// Where the ray meets the cylinder `x² + y² = radius²`.
fn cylinder(ray: &Ray, radius: f64) -> Vec<f64> {
    let (o, d) = (ray.origin.truncate(), ray.dir.truncate());
    quadratic(
        d.length_squared(),
        2.0 * o.dot(d),
        o.length_squared() - radius * radius,
    )
}

/// Where the ray meets the plane `x + y + z = level`.
fn plane(ray: &Ray, level: f64) -> Vec<f64> {
    let s = ray.dir.x + ray.dir.y + ray.dir.z;
    vec![(level - (ray.origin.x + ray.origin.y + ray.origin.z)) / s]
}

/// The direction of the normal at a point of the zero set, by its closed form (either sign).
type Outward = fn(DVec3) -> DVec3;

fn cases() -> Vec<(&'static str, Exact, Outward)> {
    // (x²+y²+z²−1)⁸ = 1e-5: r² = 1 ± 1e-5^(1/8); (x²+y²−1)⁸ = 1e-12 likewise.
    vec![
        (
            "(x+y+z+1)^4 - 1",
            |r| [plane(r, 0.0), plane(r, -2.0)].concat(),
            |_| DVec3::ONE,
        ),
        (
            "(x+y+z+1)^8 - 1",
            |r| [plane(r, 0.0), plane(r, -2.0)].concat(),
            |_| DVec3::ONE,
        ),
        (
            "(x+y+z+1)^16 - 1",
            |r| [plane(r, 0.0), plane(r, -2.0)].concat(),
            |_| DVec3::ONE,
        ),
        (
            "(x+y+z)^16 - 1",
            |r| [plane(r, 1.0), plane(r, -1.0)].concat(),
            |_| DVec3::ONE,
        ),
        (
            "(x^2+y^2+z^2-1)^8 - 1e-5",
            |r| {
                let c = 1e-5f64.powf(0.125);
                [
                    sphere(r, DVec3::ZERO, (1.0 + c).sqrt()),
                    sphere(r, DVec3::ZERO, (1.0 - c).sqrt()),
                ]
                .concat()
            },
            |p| p,
        ),
        (
            "(x^2+y^2-1)^8 - 1e-12",
            |r| {
                let c = 1e-12f64.powf(0.125);
                [cylinder(r, (1.0 + c).sqrt()), cylinder(r, (1.0 - c).sqrt())].concat()
            },
            |p| DVec3::new(p.x, p.y, 0.0),
        ),
        (
            "((x-0.5)^2+(y+0.3)^2+(z-0.2)^2)^8 = 1",
            |r| sphere(r, DVec3::new(0.5, -0.3, 0.2), 1.0),
            |p| p - DVec3::new(0.5, -0.3, 0.2),
        ),
    ]
}

/// The first exact hit in `(0, ∞)` inside the clip sphere, or `None`; `Err` when a hit lies
/// too close to the clip sphere (or two hits too close together) for the comparison to be
/// fair.
fn first_exact(ray: &Ray, exact: Exact) -> Result<Option<f64>, ()> {
    let mut hits: Vec<f64> = exact(ray)
        .into_iter()
        .filter(|t| t.is_finite() && *t > 0.0)
        .collect();
    hits.sort_by(f64::total_cmp);
    for &t in &hits {
        let r = ray.at(t).length();
        if (r - BOUND).abs() < 1e-3 {
            return Err(());
        }
        if r < BOUND {
            return Ok(Some(t));
        }
    }
    Ok(None)
}

#[test]
fn every_cliff_is_hit_where_its_closed_form_says() {
    let cam = Camera::new(DVec3::new(6.0, 1.2, 0.9), DVec3::ZERO, DVec3::Z, 32.0).unwrap();
    for (equation, exact, outward) in cases() {
        let shape = Implicit::new(equation, Frame::identity(), Some(BOUND)).unwrap();
        let (mut hits, mut compared) = (0, 0);
        let rays: Vec<Ray> = (0..N * N)
            .map(|i| cam.ray((i % N) as f64 + 0.5, (i / N) as f64 + 0.5, N, N))
            .collect();
        for group in rays.chunks_exact(LANES) {
            let four: [Ray; LANES] = std::array::from_fn(|i| group[i]);
            let lanes = shape.intersect_lanes(&four, [1e-9; LANES], [f64::INFINITY; LANES]);
            for (ray, lane) in four.iter().zip(lanes) {
                let got = shape.intersect(ray, 1e-9, f64::INFINITY);
                assert_eq!(
                    got.map(f64::to_bits),
                    lane.map(f64::to_bits),
                    "{equation}: four at once as one at a time, {ray:?}"
                );
                let Ok(want) = first_exact(ray, exact) else {
                    continue;
                };
                compared += 1;
                match (got, want) {
                    (None, None) => {}
                    (Some(t), Some(w)) => {
                        hits += 1;
                        assert!(
                            (t - w).abs() <= 1e-9 * w,
                            "{equation}: {ray:?} hit at {t}, exactly at {w}"
                        );
                        let n = shape.normal(ray.at(t));
                        let want_n = outward(ray.at(w)).normalize();
                        // Outward: along ∇f, which points away from the zero set's inside
                        // (f < 0) — for these, the side the closed form's normal names or
                        // its opposite; the direction must match up to that sign.
                        assert!(
                            (n.dot(want_n).abs() - 1.0).abs() < 1e-9,
                            "{equation}: normal {n} at {}, want ±{want_n}",
                            ray.at(t)
                        );
                    }
                    _ => panic!("{equation}: {ray:?} gives {got:?}, exactly {want:?}"),
                }
            }
        }
        assert!(
            compared > (N * N) as usize * 9 / 10,
            "{equation}: {compared}"
        );
        assert!(hits > 200, "{equation}: only {hits} hits");
    }
}
