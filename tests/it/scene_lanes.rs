//! Rays asked [`LANES`] at a time (`Scene::intersect_lanes`, as the camera rays of
//! neighbouring pixels are) get exactly the hits they get one at a time, on every shipped
//! scene and on the heart's hard rays: the same object, the same `t` and normal to the bit;
//! and shadow rays asked together (`Scene::occluded_lanes`) the same answers as alone.

use kardia::geometry::{DVec3, Ray};
use kardia::scene::{parse_file, LoadOptions, Scene, SceneHit};
use kardia::shapes::heart::heart_corpus;
use kardia::shapes::{Heart, Shape, LANES};
use std::path::Path;

fn bits(hit: &Option<SceneHit>) -> Option<(usize, u64, [u64; 3])> {
    hit.as_ref().map(|h| {
        (
            h.object,
            h.t.to_bits(),
            h.normal.to_array().map(f64::to_bits),
        )
    })
}

/// Checks `rays` in groups of `LANES`; returns how many of them hit something.
fn check(scene: &Scene, rays: &[Ray], t_min: f64, t_max: f64, what: &str) -> usize {
    let mut hits = 0;
    for group in rays.chunks_exact(LANES) {
        let lanes: [Ray; LANES] = std::array::from_fn(|i| group[i]);
        let together = scene.intersect_lanes(&lanes, t_min, t_max);
        for (ray, got) in lanes.iter().zip(&together) {
            let alone = scene.intersect(ray, t_min, t_max);
            assert_eq!(bits(got), bits(&alone), "{what}: {ray:?}");
            hits += usize::from(alone.is_some());
        }
    }
    hits
}

/// Checks `Scene::occluded_lanes` against `Scene::occluded` on `rays` in groups of `LANES`,
/// each lane with its own range (some empty, some short, some to infinity), as the shadow
/// rays of neighbouring pixels are; returns how many are blocked.
fn check_occluded(scene: &Scene, rays: &[Ray], what: &str) -> usize {
    let mut blocked = 0;
    for (k, group) in rays.chunks_exact(LANES).enumerate() {
        let lanes: [Ray; LANES] = std::array::from_fn(|i| group[i]);
        let t_min: [f64; LANES] = std::array::from_fn(|i| [1e-9, 1e-6, 0.5, 2.0][(k + i) % 4]);
        let t_max: [f64; LANES] =
            std::array::from_fn(|i| [f64::INFINITY, 3.0, 0.25, 1e-7, 20.0][(k + 2 * i) % 5]);
        let together = scene.occluded_lanes(&lanes, t_min, t_max);
        for i in 0..LANES {
            let alone = scene.occluded(&lanes[i], t_min[i], t_max[i]);
            assert_eq!(
                together[i], alone,
                "{what}: {:?} ({}, {})",
                lanes[i], t_min[i], t_max[i]
            );
            blocked += usize::from(alone);
        }
    }
    blocked
}

/// Camera rays through a jittered grid of the scene's image, in raster order.
fn camera_rays(scene: &Scene, side: u32) -> Vec<Ray> {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut jitter = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut rays = Vec::new();
    for y in 0..side {
        for x in 0..side {
            let (px, py) = (x as f64 + jitter(), y as f64 + jitter());
            rays.push(scene.camera.ray(px, py, side, side));
        }
    }
    rays
}

/// The shipped scene files, sorted.
fn shipped_scenes() -> Vec<std::path::PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut files: Vec<_> = std::fs::read_dir(&root)
        .unwrap()
        .chain(std::fs::read_dir(root.join("implicit")).unwrap())
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "scene"))
        .collect();
    files.sort();
    assert!(files.len() >= 10, "{files:?}");
    files
}

/// Secondary rays of `rays`' hits: from each hit point towards the camera, and on through
/// it (bounded by the caller, as shadow and reflected rays are).
fn secondary_rays(scene: &Scene, rays: &[Ray]) -> Vec<Ray> {
    let mut secondary = Vec::new();
    for ray in rays {
        if let Some(hit) = scene.intersect(ray, 0.0, f64::INFINITY) {
            secondary.push(Ray::new(hit.point, -ray.dir));
            secondary.push(Ray::new(hit.point, ray.dir));
        }
    }
    secondary
}

#[test]
fn every_shipped_scene_gives_the_same_hits_in_lanes() {
    let mut blocked = 0;
    for file in shipped_scenes() {
        let scene = parse_file(&file, &LoadOptions::default()).unwrap();
        let what = file.display().to_string();
        let rays = camera_rays(&scene, 48);
        let hits = check(&scene, &rays, 0.0, f64::INFINITY, &what);
        assert!(hits > 0, "{what}: no camera ray hits");
        let secondary = secondary_rays(&scene, &rays);
        check(&scene, &secondary, 1e-9, 20.0, &what);
        blocked += check_occluded(&scene, &secondary, &what);
    }
    assert!(blocked > 1000, "{blocked} shadow-style rays blocked");
}

/// A scene of one object asks it without the box test (`Scene::box_tests_skipped`): every
/// object of every shipped scene, alone in its scene, gives the answers its box test and its
/// shape give together (the same `t` to the bit, the same shadow answers), one ray at a
/// time and in lanes.
#[test]
fn an_object_alone_gives_the_same_hits_without_the_box_test() {
    let mut shapes = std::collections::BTreeSet::new();
    let (mut hits, mut misses_of_the_box) = (0, 0);
    for file in shipped_scenes() {
        let count = parse_file(&file, &LoadOptions::default())
            .unwrap()
            .objects
            .len();
        for keep in 0..count {
            let mut scene = parse_file(&file, &LoadOptions::default()).unwrap();
            let object = scene.objects.swap_remove(keep);
            shapes.insert(object.keyword);
            scene.objects = vec![object];
            assert!(scene.box_tests_skipped());
            let what = format!("{}, object {keep} alone", file.display());
            let camera = camera_rays(&scene, 32);
            let secondary = secondary_rays(&scene, &camera);
            let object = &scene.objects[0];
            for (rays, t_min, t_max) in [(&camera, 0.0, f64::INFINITY), (&secondary, 1e-9, 20.0)] {
                check(&scene, rays, t_min, t_max, &what);
                for ray in rays {
                    let boxed = object.bounds.clip(ray, t_min, t_max);
                    misses_of_the_box += usize::from(boxed.is_none());
                    let want = boxed.and_then(|_| object.shape.intersect(ray, t_min, t_max));
                    let got = scene.intersect(ray, t_min, t_max);
                    assert_eq!(
                        got.map(|h| h.t.to_bits()),
                        want.map(f64::to_bits),
                        "{what}: {ray:?}"
                    );
                    let occluded = boxed.is_some() && object.shape.occludes(ray, t_min, t_max);
                    assert_eq!(
                        scene.occluded(ray, t_min, t_max),
                        occluded,
                        "{what}: {ray:?}"
                    );
                    hits += usize::from(got.is_some());
                }
            }
            check_occluded(&scene, &secondary, &what);
        }
    }
    // Every kind of object, and rays on both sides of their boxes.
    for keyword in [
        "HEART",
        "IMPLICIT",
        "SPHERE",
        "PLANE",
        "BOX",
        "ELLIPSOID",
        "POLYGON",
    ] {
        assert!(shapes.contains(keyword), "no {keyword} alone: {shapes:?}");
    }
    assert!(
        hits > 1000 && misses_of_the_box > 1000,
        "{hits} hits, {misses_of_the_box} misses of the box"
    );
}

#[test]
fn the_hearts_corpus_and_hard_rays_give_the_same_hits_in_lanes() {
    // The corpus rays (origins outside the box; many miss) and the hard rays (multiple
    // roots, tangencies, the equator), with every fourth lane idle or bounded short.
    let heart = Heart::new(DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z).unwrap();
    let rays: Vec<Ray> = heart_corpus()
        .iter()
        .map(|c| Ray::new(c.origin, c.dir))
        .collect();
    let mut hits = 0;
    for (k, group) in rays.chunks_exact(LANES).enumerate() {
        let lanes: [Ray; LANES] = std::array::from_fn(|i| group[i]);
        let t_max: [f64; LANES] = std::array::from_fn(|i| match (k + i) % 4 {
            0 => f64::NEG_INFINITY,
            1 => 2.0,
            _ => f64::INFINITY,
        });
        let together = heart.intersect_lanes(&lanes, [0.0; LANES], t_max);
        for i in 0..LANES {
            let alone = heart.intersect(&lanes[i], 0.0, t_max[i]);
            assert_eq!(
                together[i].map(f64::to_bits),
                alone.map(f64::to_bits),
                "{:?}",
                lanes[i]
            );
            hits += usize::from(alone.is_some());
        }
    }
    assert!(hits > 500, "{hits}");
}
