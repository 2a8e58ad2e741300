//! The hard cases of shared/notes/heart-math.md, one named test each, run on the geometry
//! alone (the brute-force root finder of `heart_support`, not the `roots` module; see
//! `heart_solvers.rs` for the same cases through every real solver).

use crate::heart_support;

use heart_support::brute_intersect;
use heart_support::cases::{self, HitFn};
use kardia::geometry::DVec3;

const BRUTE: HitFn = &brute_intersect;

#[test]
fn hard_case_rays_in_the_z0_plane_have_triple_roots() {
    cases::z0_plane_triple_roots(BRUTE);
}

#[test]
fn hard_case_equator_curve_hits_and_normals_are_exact() {
    let (dist, angle) = cases::equator_hits_are_exact(BRUTE, 300);
    println!("equator: worst distance {dist:e}, worst normal angle {angle:e} rad");
}

#[test]
fn hard_case_tangent_rays_double_roots() {
    cases::tangent_rays(BRUTE);
}

#[test]
fn hard_case_rays_through_and_beside_the_singular_points() {
    cases::singular_points(BRUTE);
}

#[test]
fn hard_case_rays_starting_on_the_surface_unit_scale() {
    assert!(cases::rays_leaving_the_surface(BRUTE, 1.0, DVec3::new(0.5, -0.2, 0.1)) > 250);
}

#[test]
fn hard_case_rays_starting_on_the_surface_tiny_heart() {
    let s = 1e-3;
    assert!(cases::rays_leaving_the_surface(BRUTE, s, DVec3::new(2.0, -1.0, 0.5) * s) > 250);
}

#[test]
fn hard_case_rays_starting_on_the_surface_huge_heart() {
    let s = 1e3;
    assert!(cases::rays_leaving_the_surface(BRUTE, s, DVec3::new(2.0, -1.0, 0.5) * s) > 250);
}

#[test]
fn hard_case_rays_starting_on_the_surface_tiny_heart_far_away() {
    assert!(cases::rays_leaving_the_surface(BRUTE, 1e-3, DVec3::new(700.0, -300.0, 50.0)) > 250);
}

#[test]
fn rays_starting_inside_exit_once() {
    cases::rays_from_inside(BRUTE);
}

#[test]
fn rays_parallel_to_each_axis() {
    cases::rays_parallel_to_each_axis(BRUTE);
}

#[test]
fn hard_case_equator_curve_no_specks_in_a_render() {
    let n = cases::no_specks_along_the_equator(BRUTE, 320);
    println!("{n} pixels near the equator checked");
    assert!(n > 300, "{n}");
}
