//! Measurements behind the design choices (run with `--ignored --nocapture`): forming the
//! per-ray polynomial by composition versus interpolation at Chebyshev points.

use kardia::camera::Camera;
use kardia::geometry::{DVec3, Frame, Ray};
use kardia::roots::Solver;
use kardia::shapes::implicit::poly::Compiled;
use kardia::shapes::implicit::{self, preset_equation, Implicit};
use kardia::shapes::Shape;
use rand::{Rng, SeedableRng};
use std::time::Instant;

/// Monomial coefficients of the degree-n interpolant of `f` at the n+1 Chebyshev points.
fn interpolate(f: impl Fn(f64) -> f64, n: usize) -> Vec<f64> {
    let m = n + 1;
    let th: Vec<f64> = (0..m)
        .map(|k| std::f64::consts::PI * (k as f64 + 0.5) / m as f64)
        .collect();
    let vals: Vec<f64> = th.iter().map(|t| f(t.cos())).collect();
    // Chebyshev coefficients by the discrete cosine transform.
    let mut cheb = vec![0.0; m];
    for (j, c) in cheb.iter_mut().enumerate() {
        let s: f64 = vals
            .iter()
            .zip(&th)
            .map(|(v, t)| v * (j as f64 * t).cos())
            .sum();
        *c = s * 2.0 / m as f64;
    }
    cheb[0] *= 0.5;
    // Σ c_j T_j → monomials, with T_j built by the recurrence.
    let mut out = vec![0.0; m];
    let mut tp = vec![0.0; m];
    let mut tc = vec![0.0; m];
    tp[0] = 1.0;
    tc[1.min(n)] = 1.0;
    for (j, &c) in cheb.iter().enumerate() {
        let t = if j == 0 { &tp } else { &tc };
        for k in 0..m {
            out[k] += c * t[k];
        }
        // Advance: T_{j+1} = 2s·T_j − T_{j−1}.
        if j >= 1 && j + 1 < m {
            let mut next = vec![0.0; m];
            for k in 0..m - 1 {
                next[k + 1] += 2.0 * tc[k];
            }
            for k in 0..m {
                next[k] -= tp[k];
            }
            tp = std::mem::replace(&mut tc, next);
        }
    }
    out
}

#[test]
#[ignore]
fn composition_versus_interpolation() {
    let mut r = rand_pcg::Pcg64::seed_from_u64(7);
    for eq in [
        "(x^2+y^2+z^2)^8 - 1".to_string(),
        preset_equation("chmutov", &[16.0]).unwrap(),
        preset_equation("barth_sextic", &[]).unwrap(),
    ] {
        let shape = Implicit::new(&eq, Frame::identity(), Some(1.8)).unwrap();
        let c = Compiled::new(&implicit::expand(&eq).unwrap());
        let n = c.degree;
        let (mut err_c, mut err_i) = (0.0f64, 0.0f64);
        let mut rays = Vec::new();
        while rays.len() < 2000 {
            let o = DVec3::new(r.random_range(-5.0..5.0), r.random_range(-5.0..5.0), 6.0);
            let d = (DVec3::new(r.random_range(-1.0..1.0), r.random_range(-1.0..1.0), 0.0) - o)
                .normalize();
            let ray = Ray::new(o, d);
            if let Some(rp) = shape.ray_polynomial(&ray) {
                rays.push((ray, rp));
            }
        }
        let t0 = Instant::now();
        let mut sink = 0.0;
        for (ray, rp) in &rays {
            let _ = ray;
            sink += shape.ray_polynomial(ray).unwrap().coeffs[0] + rp.t_mid * 0.0;
        }
        let t_comp = t0.elapsed().as_secs_f64() / rays.len() as f64;
        let t0 = Instant::now();
        for (ray, rp) in &rays {
            let f = |s: f64| c.eval(ray.at(rp.t_mid + s * rp.t_half).to_array());
            sink += interpolate(f, n)[0];
        }
        let t_int = t0.elapsed().as_secs_f64() / rays.len() as f64;
        for (ray, rp) in &rays {
            let f = |s: f64| c.eval(ray.at(rp.t_mid + s * rp.t_half).to_array());
            let ic = interpolate(f, n);
            let scale = rp.coeffs.iter().map(|k| k.abs()).fold(0.0, f64::max);
            for k in 0..=20 {
                let s = -1.0 + k as f64 / 10.0;
                let direct = f(s);
                let pc = rp.coeffs.iter().rev().fold(0.0, |a, k| a * s + k);
                let pi = ic.iter().rev().fold(0.0, |a, k| a * s + k);
                err_c = err_c.max((pc - direct).abs() / scale);
                err_i = err_i.max((pi - direct).abs() / scale);
            }
        }
        println!(
            "degree {n} ({} terms): composition {:.2} µs, max rel err {err_c:.1e}; interpolation {:.2} µs, max rel err {err_i:.1e} [{sink:.0e}]",
            c.terms.len(),
            t_comp * 1e6,
            t_int * 1e6
        );
    }
}

#[test]
#[ignore]
fn intersection_cost_per_ray() {
    let cam = Camera::new(DVec3::new(6.0, 1.2, 0.9), DVec3::ZERO, DVec3::Z, 32.0).unwrap();
    let n = 200u32;
    for (name, params) in [
        ("heart", vec![]),
        ("taubin_heart", vec![]),
        ("torus", vec![1.0, 0.3]),
        ("barth_sextic", vec![]),
        ("chmutov", vec![16.0]),
    ] {
        for &(solver, sname) in Solver::ALL {
            let s = Implicit::from_preset(name, &params, Frame::identity(), None)
                .unwrap()
                .with_solver(solver);
            let t0 = Instant::now();
            let mut hits = 0;
            for i in 0..n * n {
                let ray = cam.ray((i % n) as f64 + 0.5, (i / n) as f64 + 0.5, n, n);
                hits += s.intersect(&ray, 1e-9, f64::INFINITY).is_some() as u32;
            }
            let dt = t0.elapsed().as_secs_f64() / (n * n) as f64;
            println!(
                "{name} {params:?} {sname}: {:.2} µs per ray, {hits} hits",
                dt * 1e6
            );
        }
    }
}

/// Per preset and solver: primary rays whose first hit disagrees with dense sampling of f.
#[test]
#[ignore]
fn solvers_against_dense_sampling() {
    for (name, params) in [
        ("chmutov", vec![16.0]),
        ("chmutov", vec![8.0]),
        ("barth_sextic", vec![]),
        ("kummer", vec![1.14]),
    ] {
        let base = Implicit::from_preset(name, &params, Frame::identity(), None).unwrap();
        let n = 96u32;
        let cam = Camera::new(
            DVec3::new(5.0, 4.0, 3.0) * base.bound() / 1.75,
            DVec3::ZERO,
            DVec3::Z,
            40.0,
        )
        .unwrap();
        for (solver, sname) in Solver::ALL {
            let shape = base.clone().with_solver(*solver);
            let (mut wrong, mut hits) = (0, 0);
            let t0 = std::time::Instant::now();
            for i in 0..n * n {
                let ray = cam.ray((i % n) as f64 + 0.5, (i / n) as f64 + 0.5, n, n);
                let hit = shape.intersect(&ray, 1e-9, f64::INFINITY);
                hits += hit.is_some() as u32;
                let Some(rp) = shape.ray_polynomial(&ray) else {
                    if hit.is_some() {
                        wrong += 1
                    };
                    continue;
                };
                let samples = 4000;
                let f = |k: i32| {
                    shape.value(
                        ray.at(rp.t_mid + rp.t_half * (2.0 * k as f64 / samples as f64 - 1.0)),
                    )
                };
                let first = f(0);
                let reference = (1..=samples)
                    .find(|&k| (f(k) > 0.0) != (first > 0.0))
                    .map(|k| rp.t_mid + rp.t_half * (2.0 * k as f64 / samples as f64 - 1.0));
                match (hit, reference) {
                    (Some(a), Some(b)) => {
                        if (a - b).abs() > 2.0 * rp.t_half / samples as f64 + 1e-9 {
                            wrong += 1
                        }
                    }
                    (None, None) => {}
                    _ => wrong += 1,
                }
            }
            println!("{name} {params:?} {sname}: hits {hits}, disagree with dense sampling {wrong} ({:.2}s)", t0.elapsed().as_secs_f64());
        }
    }
}
