//! Shading checks with known answers: Lambert's law, mirror geometry, Snell's law through a
//! sphere, total internal reflection, Beer–Lambert, shadows, sampling determinism.

use crate::render_support;

use kardia::geometry::{DVec3, Ray};
use kardia::materials::Material;
use render_support::*;

fn settings(spp: u32) -> RenderSettings {
    RenderSettings {
        spp,
        max_depth: 8,
        seed: 1,
        threads: 2,
    }
}

fn close(a: DVec3, b: DVec3, tol: f64) -> bool {
    (a - b).abs().max_element() <= tol
}

/// A diffuse sphere under one point light: every pixel follows `ambient·c + c·L·max(0, n·l)`.
#[test]
fn diffuse_sphere_follows_lamberts_law() {
    let (w, h) = (40, 40);
    let eye = DVec3::new(0.0, -5.0, 0.0);
    let mut s = scene(w, h, eye, DVec3::ZERO, 40.0);
    s.ambient = DVec3::splat(0.1);
    let c = DVec3::new(0.8, 0.6, 0.4);
    sphere(&mut s, DVec3::ZERO, 1.0, Material::diffuse(c));
    let lpos = DVec3::new(4.0, -6.0, 5.0);
    let lcol = DVec3::new(1.0, 0.9, 0.8);
    light(&mut s, lpos, lcol, 0.0);

    let expected_along = |ray: &Ray| -> Option<DVec3> {
        let t = hit_sphere(ray.origin, ray.dir, DVec3::ZERO, 1.0)?;
        let p = ray.at(t);
        let n = p.normalize();
        let l = (lpos - p).normalize();
        Some(s.ambient * c + c * lcol * n.dot(l).max(0.0))
    };

    // Exact rays through pixel centres.
    let st = settings(1);
    let mut checked = 0;
    let mut lit = 0;
    for y in (0..h).step_by(3) {
        for x in (0..w).step_by(3) {
            let ray = s.camera.ray(x as f64 + 0.5, y as f64 + 0.5, w, h);
            let got = trace_ray(&s, &st, &ray);
            match expected_along(&ray) {
                Some(e) => {
                    assert!(close(got, e, 1e-9), "pixel ({x},{y}): {got} vs {e}");
                    checked += 1;
                    if e.x > s.ambient.x * c.x + 1e-3 {
                        lit += 1;
                    }
                }
                None => assert_eq!(got, s.background),
            }
        }
    }
    assert!(checked > 40 && lit > 20, "checked {checked}, lit {lit}");

    // The rendered image agrees away from the silhouette (supersampling averages a small,
    // smooth neighbourhood there).
    let img = render(&s, &settings(16));
    for y in (2..h - 2).step_by(2) {
        for x in (2..w - 2).step_by(2) {
            let corners = [(-1.0, -1.0), (2.0, -1.0), (-1.0, 2.0), (2.0, 2.0)];
            let all_hit = corners.iter().all(|(dx, dy)| {
                let r = s.camera.ray(x as f64 + dx, y as f64 + dy, w, h);
                hit_sphere(r.origin, r.dir, DVec3::ZERO, 1.0).is_some()
            });
            if all_hit {
                let ray = s.camera.ray(x as f64 + 0.5, y as f64 + 0.5, w, h);
                let e = expected_along(&ray).unwrap();
                let got = img.get(x, y);
                assert!(close(got, e, 0.03), "pixel ({x},{y}): {got} vs {e}");
            }
        }
    }
}

/// A mirror floor shows the red ball exactly where the reflected ray meets the ball.
#[test]
fn mirror_shows_the_reflection_where_geometry_says() {
    let (w, h) = (48, 36);
    let eye = DVec3::new(0.0, -6.0, 1.5);
    let mut s = scene(w, h, eye, DVec3::new(0.0, 0.0, -0.3), 45.0);
    s.background = DVec3::new(0.0, 0.0, 1.0);
    s.ambient = DVec3::ONE;
    let centre = DVec3::new(0.0, 0.0, 0.2);
    let radius = 0.6;
    let red = DVec3::new(1.0, 0.0, 0.0);
    sphere(&mut s, centre, radius, Material::diffuse(red));
    let mirror = Material {
        diffuse: DVec3::ZERO,
        reflect: 1.0,
        ..Material::default()
    };
    let floor_z = -0.5;
    plane(&mut s, DVec3::new(0.0, 0.0, floor_z), DVec3::Z, mirror);

    let classify = |ray: &Ray| -> DVec3 {
        let ts = hit_sphere(ray.origin, ray.dir, centre, radius);
        let tp = (floor_z - ray.origin.z) / ray.dir.z;
        let tp = (tp > 0.0).then_some(tp);
        match (ts, tp) {
            (Some(a), Some(b)) if a < b => red,
            (Some(_), None) => red,
            (_, Some(t)) => {
                let p = ray.at(t);
                let d = ray.dir * DVec3::new(1.0, 1.0, -1.0);
                if hit_sphere(p, d, centre, radius).is_some() {
                    red
                } else {
                    s.background
                }
            }
            (None, None) => s.background,
        }
    };

    let st = settings(1);
    let mut reflected_red = 0;
    for y in 0..h {
        for x in 0..w {
            let ray = s.camera.ray(x as f64 + 0.5, y as f64 + 0.5, w, h);
            let e = classify(&ray);
            let got = trace_ray(&s, &st, &ray);
            assert!(close(got, e, 1e-9), "pixel ({x},{y}): {got} vs {e}");
            let below_horizon = hit_sphere(ray.origin, ray.dir, centre, radius).is_none()
                && ray.dir.z < 0.0
                && e == red;
            if below_horizon {
                reflected_red += 1;
            }
        }
    }
    assert!(reflected_red > 20, "only {reflected_red} reflected pixels");

    // With no recursion the mirror is black: only its (zero) diffuse colour remains.
    let flat = RenderSettings {
        max_depth: 0,
        ..settings(1)
    };
    let ray = s.camera.ray(w as f64 * 0.5, h as f64 - 0.5, w, h);
    assert_eq!(trace_ray(&s, &flat, &ray), DVec3::ZERO);
}

/// A ray through a glass ball (ior 1.5) follows Snell's law in and out: a small target
/// placed on the analytically refracted path is seen, dimmed by the two Fresnel losses.
#[test]
fn refraction_follows_snells_law() {
    let mut s = scene(8, 8, DVec3::new(0.0, -5.0, 0.0), DVec3::ZERO, 30.0);
    s.ambient = DVec3::ONE;
    let glass = Material {
        diffuse: DVec3::ZERO,
        transmit: 1.0,
        ior: 1.5,
        ..Material::default()
    };
    sphere(&mut s, DVec3::ZERO, 1.0, glass);

    let refract = |d: DVec3, n: DVec3, eta: f64| -> (DVec3, f64) {
        let cos_i = -d.dot(n);
        let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
        let cos_t = (1.0 - sin2_t).sqrt();
        let rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
        let rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
        (
            eta * d + (eta * cos_i - cos_t) * n,
            0.5 * (rs * rs + rp * rp),
        )
    };
    let o = DVec3::new(0.0, -5.0, 0.0);
    let d = DVec3::new(0.0, 5.0, 0.45).normalize();
    let t1 = hit_sphere(o, d, DVec3::ZERO, 1.0).unwrap();
    let p1 = o + t1 * d;
    let (d1, f1) = refract(d, p1.normalize(), 1.0 / 1.5);
    let d1 = d1.normalize();
    let t2 = hit_sphere(p1, d1, DVec3::ZERO, 1.0).unwrap();
    let p2 = p1 + t2 * d1;
    let (d2, f2) = refract(d1, -p2.normalize(), 1.5);
    let d2 = d2.normalize();
    assert!(d2.z < -0.1, "the ball bends the ray toward the axis: {d2}");

    let target = p2 + 3.0 * d2;
    sphere(
        &mut s,
        target,
        0.05,
        Material::diffuse(DVec3::new(1.0, 0.0, 0.0)),
    );
    let got = trace_ray(&s, &settings(1), &Ray::new(o, d));
    let expected = (1.0 - f1) * (1.0 - f2);
    assert!(
        (got.x - expected).abs() < 1e-9 && got.y.abs() < 1e-12,
        "{got} vs {expected}"
    );

    // The undeviated path would miss the target.
    let straight = p1 + 3.0 * d;
    assert!((straight - target).length() > 0.2);
}

/// From inside a glass ball, a ray meeting the surface beyond the critical angle is totally
/// reflected (and keeps being so), while a steeper one escapes.
#[test]
fn total_internal_reflection() {
    let mut s = scene(8, 8, DVec3::new(0.0, -5.0, 0.0), DVec3::ZERO, 30.0);
    s.background = DVec3::ONE;
    let glass = Material {
        diffuse: DVec3::ZERO,
        transmit: 1.0,
        ior: 1.5,
        ..Material::default()
    };
    sphere(&mut s, DVec3::ZERO, 1.0, glass);
    let st = settings(1);
    // sin θ = 0.9 > 1/1.5: trapped forever, so nothing but black comes back.
    let trapped = trace_ray(&s, &st, &Ray::new(DVec3::new(0.9, 0.0, 0.0), DVec3::Y));
    assert_eq!(trapped, DVec3::ZERO);
    // sin θ = 0.3: most of the light escapes to the white background.
    let escapes = trace_ray(&s, &st, &Ray::new(DVec3::new(0.3, 0.0, 0.0), DVec3::Y));
    assert!(escapes.x > 0.9, "{escapes}");
    // With ior 1 there is no interface at all.
    s.objects[0].material.ior = 1.0;
    let clear = trace_ray(&s, &st, &Ray::new(DVec3::new(0.9, 0.0, 0.0), DVec3::Y));
    assert!(close(clear, DVec3::ONE, 1e-12), "{clear}");
}

/// Light crossing an absorbing ball of index 1 along a diameter keeps `exp(−a·2r)`.
#[test]
fn beer_lambert_inside_a_transmissive_ball() {
    let mut s = scene(8, 8, DVec3::new(0.0, -5.0, 0.0), DVec3::ZERO, 30.0);
    s.background = DVec3::ONE;
    let a = DVec3::new(0.1, 0.5, 2.0);
    let glass = Material {
        diffuse: DVec3::ZERO,
        transmit: 1.0,
        ior: 1.0,
        attenuation: a,
        ..Material::default()
    };
    sphere(&mut s, DVec3::ZERO, 0.75, glass);
    let got = trace_ray(
        &s,
        &settings(1),
        &Ray::new(DVec3::new(0.0, -5.0, 0.0), DVec3::Y),
    );
    let e = (-a * 1.5).exp();
    assert!(close(got, e, 1e-12), "{got} vs {e}");
}

/// Shadows: an opaque ball blocks the light; a transmissive one dims it by kt per surface
/// crossed and tints it by its absorption.
#[test]
fn shadows_block_or_tint() {
    let mut s = scene(8, 8, DVec3::new(5.0, 0.0, 3.0), DVec3::ZERO, 40.0);
    s.ambient = DVec3::splat(0.1);
    plane(&mut s, DVec3::ZERO, DVec3::Z, Material::diffuse(DVec3::ONE));
    sphere(&mut s, DVec3::new(0.0, 0.0, 1.0), 0.5, Material::default());
    light(&mut s, DVec3::new(0.0, 0.0, 5.0), DVec3::ONE, 0.0);
    let st = settings(1);
    let towards = |p: DVec3| {
        let o = DVec3::new(3.0, 0.0, 0.5);
        Ray::new(o, p - o)
    };
    let shadowed = trace_ray(&s, &st, &towards(DVec3::ZERO));
    assert!(close(shadowed, DVec3::splat(0.1), 1e-12), "{shadowed}");
    let p = DVec3::new(2.0, 0.0, 0.0);
    let lit = trace_ray(&s, &st, &towards(p));
    let cos = (DVec3::new(0.0, 0.0, 5.0) - p).normalize().z;
    assert!(close(lit, DVec3::splat(0.1 + cos), 1e-12), "{lit}");

    let a = DVec3::new(0.0, 0.7, 1.4);
    s.objects[1].material = Material {
        transmit: 0.5,
        attenuation: a,
        ..Material::default()
    };
    let tinted = trace_ray(&s, &st, &towards(DVec3::ZERO));
    let e = DVec3::splat(0.1) + 0.25 * (-a * 1.0).exp();
    assert!(close(tinted, e, 1e-12), "{tinted} vs {e}");
}

/// The back side of a surface uses `Material::inside` when set.
#[test]
fn inside_colour_on_back_faces() {
    let mut s = scene(8, 8, DVec3::new(0.0, -5.0, 0.0), DVec3::ZERO, 30.0);
    s.ambient = DVec3::ONE;
    let m = Material {
        diffuse: DVec3::new(1.0, 0.0, 0.0),
        inside: Some(DVec3::new(0.0, 1.0, 0.0)),
        ..Material::default()
    };
    sphere(&mut s, DVec3::ZERO, 1.0, m);
    let st = settings(1);
    let outside = trace_ray(&s, &st, &Ray::new(DVec3::new(0.0, -5.0, 0.0), DVec3::Y));
    let inside = trace_ray(&s, &st, &Ray::new(DVec3::ZERO, DVec3::Y));
    assert_eq!(outside, DVec3::new(1.0, 0.0, 0.0));
    assert_eq!(inside, DVec3::new(0.0, 1.0, 0.0));
}

/// A spherical light gives a penumbra; images depend on the seed only, not on threads.
#[test]
fn soft_shadows_are_deterministic() {
    let mut s = scene(32, 32, DVec3::new(0.0, -0.01, 6.0), DVec3::ZERO, 50.0);
    plane(&mut s, DVec3::ZERO, DVec3::Z, Material::diffuse(DVec3::ONE));
    sphere(&mut s, DVec3::new(0.0, 0.0, 1.0), 0.6, Material::default());
    light(&mut s, DVec3::new(0.0, 0.0, 4.0), DVec3::ONE, 1.0);
    let mut one = settings(9);
    one.threads = 1;
    let a = render(&s, &one);
    let b = render(&s, &settings(9));
    assert_eq!(a, b, "thread count changed the image");
    let c = render(
        &s,
        &RenderSettings {
            seed: 2,
            ..settings(9)
        },
    );
    assert_ne!(a, c, "the seed had no effect");
    // Pixels strictly between umbra and full light exist: the penumbra.
    let lpos = DVec3::new(0.0, 0.0, 4.0);
    let mut partial = 0;
    let mut full = 0;
    for y in 0..32 {
        for x in 0..32 {
            let r = s.camera.ray(x as f64 + 0.5, y as f64 + 0.5, 32, 32);
            let p = r.at(-r.origin.z / r.dir.z);
            let unshadowed = (lpos - p).normalize().z;
            let v = a.get(x, y).x;
            if v > 0.05 && v < 0.8 * unshadowed {
                partial += 1;
            }
            if v > 0.97 * unshadowed {
                full += 1;
            }
        }
    }
    assert!(partial > 20, "{partial} penumbra pixels");
    assert!(full > 100, "{full} fully lit pixels");
}

/// More shadow samples per pixel sample for a spherical light: the same penumbra on
/// average (the estimate is unbiased), less noise against a many-sample reference, and the
/// extra shadow rays counted.
#[test]
fn light_samples_smooth_the_penumbra() {
    let build = |samples: u32| {
        let mut s = scene(48, 48, DVec3::new(0.0, -0.01, 6.0), DVec3::ZERO, 50.0);
        plane(&mut s, DVec3::ZERO, DVec3::Z, Material::diffuse(DVec3::ONE));
        sphere(&mut s, DVec3::new(0.0, 0.0, 1.0), 0.6, Material::default());
        light(&mut s, DVec3::new(0.0, 0.0, 4.0), DVec3::ONE, 1.0);
        s.lights[0].samples = samples;
        s
    };
    let reference = render(&build(64), &settings(16));
    let error = |samples: u32| {
        let (image, stats) = render_with_progress(&build(samples), &settings(1), &|_| {});
        let (mut squares, mut sum, mut reference_sum) = (0.0, 0.0, 0.0);
        for (a, b) in image.pixels.iter().zip(&reference.pixels) {
            let d = (a.x - b.x) as f64;
            squares += d * d;
            sum += a.x as f64;
            reference_sum += b.x as f64;
        }
        let n = image.pixels.len() as f64;
        ((squares / n).sqrt(), (sum - reference_sum) / n, stats.rays)
    };
    let (noisy, bias_1, rays_1) = error(1);
    let (smooth, bias_16, rays_16) = error(16);
    assert!(
        smooth < 0.4 * noisy,
        "RMS error {noisy:.4} with 1 shadow sample, {smooth:.4} with 16"
    );
    assert!(
        bias_1.abs() < 0.01 && bias_16.abs() < 0.01,
        "{bias_1} {bias_16}"
    );
    // Every pixel sees the plane or the sphere: one primary ray, then 1 or 16 shadow rays
    // wherever the surface faces the light.
    assert!(rays_16 > rays_1 + 10 * 48 * 48, "{rays_1} → {rays_16}");
}

/// Every ray is counted: a view filled by one lit plane costs a primary and a shadow ray
/// per sample; an empty scene costs one primary ray per sample.
#[test]
fn ray_counts() {
    let mut s = scene(20, 10, DVec3::new(0.0, 0.0, 5.0), DVec3::ZERO, 30.0);
    let (_, stats) = render_with_progress(&s, &settings(4), &|_| {});
    assert_eq!(stats.rays, 20 * 10 * 4);
    plane(&mut s, DVec3::ZERO, DVec3::Z, Material::default());
    light(&mut s, DVec3::new(0.0, 0.0, 3.0), DVec3::ONE, 0.0);
    let done = std::sync::atomic::AtomicU64::new(0);
    let (img, stats) = render_with_progress(&s, &settings(4), &|n| {
        done.fetch_add(n, std::sync::atomic::Ordering::Relaxed);
    });
    assert_eq!(stats.rays, 2 * 20 * 10 * 4);
    assert_eq!(done.into_inner(), 200);
    assert_eq!(stats.threads, 2);
    assert_eq!((img.width, img.height, img.pixels.len()), (20, 10, 200));
}

/// Scale invariance: the same scene at 1e-3 and 1e3 scale renders the same image (the
/// self-intersection guard follows the scene's size).
#[test]
fn scale_invariant_rendering() {
    let build = |k: f64| {
        let mut s = scene(24, 24, DVec3::new(3.0, -4.0, 2.5) * k, DVec3::ZERO, 40.0);
        s.ambient = DVec3::splat(0.05);
        plane(
            &mut s,
            DVec3::new(0.0, 0.0, -k),
            DVec3::Z,
            Material {
                reflect: 0.3,
                ..Material::diffuse(DVec3::splat(0.5))
            },
        );
        sphere(
            &mut s,
            DVec3::ZERO,
            k,
            Material {
                transmit: 0.8,
                ior: 1.4,
                attenuation: DVec3::new(0.2, 0.4, 0.8) / k,
                diffuse: DVec3::splat(0.1),
                specular: 0.5,
                ..Material::default()
            },
        );
        light(&mut s, DVec3::new(2.0, -3.0, 5.0) * k, DVec3::ONE, 0.3 * k);
        s
    };
    let st = settings(4);
    let small = render(&build(1e-3), &st);
    let big = render(&build(1e3), &st);
    let unit = render(&build(1.0), &st);
    for (i, ((a, b), c)) in small
        .pixels
        .iter()
        .zip(&big.pixels)
        .zip(&unit.pixels)
        .enumerate()
    {
        assert!(
            close(a.as_dvec3(), c.as_dvec3(), 1e-6) && close(b.as_dvec3(), c.as_dvec3(), 1e-6),
            "pixel {i}: {a} {b} {c}"
        );
    }
}
