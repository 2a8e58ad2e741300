//! The render API (`kardia::pipeline`): regions that join into the whole image, cancellation,
//! progress, re-rendering one loaded scene, study views, finite pixels, and the CLI's
//! `--region` and `--view`.

use crate::cli_render::listing;
use kardia::camera::Camera;
use kardia::film::{self, Image, ImageFormat, Region};
use kardia::geometry::DVec3;
use kardia::lights::Light;
use kardia::pipeline::{
    CancelToken, Control, Priority, Progress, RenderError, RenderRequest, Rendered, Renderer, View,
};
use kardia::scene::{self, LoadOptions, Scene};
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

fn default_heart() -> Scene {
    scene::parse(scene::DEFAULT_SCENE, "heart.scene", &LoadOptions::default()).unwrap()
}

/// 64×53 of the default heart at 2 spp, depth 4, seed 5 (small, but with soft shadows and a
/// reflecting floor, so every sample's random numbers matter).
fn small_request() -> RenderRequest {
    RenderRequest {
        width: Some(64),
        height: Some(53),
        spp: 2,
        max_depth: 4,
        seed: 5,
        ..RenderRequest::default()
    }
}

/// The four quarters of a `w × h` image, cut off the tile grid (at 27 and 22).
fn quarters(w: u32, h: u32) -> [Region; 4] {
    let (cx, cy) = (27, 22);
    [
        Region {
            x: 0,
            y: 0,
            width: cx,
            height: cy,
        },
        Region {
            x: cx,
            y: 0,
            width: w - cx,
            height: cy,
        },
        Region {
            x: 0,
            y: cy,
            width: cx,
            height: h - cy,
        },
        Region {
            x: cx,
            y: cy,
            width: w - cx,
            height: h - cy,
        },
    ]
}

fn read_exr(path: &Path) -> Vec<(f32, f32, f32)> {
    let image = exr::prelude::read_first_rgba_layer_from_file(
        path,
        |res, _| {
            (
                res.width(),
                vec![(0.0f32, 0.0f32, 0.0f32); res.width() * res.height()],
            )
        },
        |(w, v), pos, (r, g, b, _a): (f32, f32, f32, f32)| v[pos.y() * *w + pos.x()] = (r, g, b),
    )
    .unwrap();
    image.layer_data.channel_data.pixels.1
}

/// Four regions rendered at once by four threads sharing one renderer and one loaded scene,
/// each written atomically to its own PNG and EXR, join into the whole image: the same
/// 8-bit bytes and the same float bits.
#[test]
fn four_regions_in_four_threads_join_into_the_whole_image() {
    let scene = Arc::new(default_heart());
    let renderer = Arc::new(Renderer::new(2).unwrap());
    let dir = tempfile::tempdir().unwrap();
    let request = small_request();
    let whole = renderer
        .render(&scene, &request, &Control::default())
        .unwrap();
    let (w, h) = (whole.full_width, whole.full_height);
    assert_eq!((w, h), (64, 53));
    film::write_image(&whole.image, &dir.path().join("whole.png")).unwrap();
    film::write_image(&whole.image, &dir.path().join("whole.exr")).unwrap();

    let regions = quarters(w, h);
    let handles: Vec<_> = regions
        .iter()
        .enumerate()
        .map(|(i, &region)| {
            let (scene, renderer) = (Arc::clone(&scene), Arc::clone(&renderer));
            let request = RenderRequest {
                region: Some(region),
                ..request.clone()
            };
            let dir = dir.path().to_path_buf();
            std::thread::spawn(move || {
                let part = renderer
                    .render(&scene, &request, &Control::default())
                    .unwrap();
                for ext in ["png", "exr"] {
                    let path = dir.join(format!("part{i}.{ext}"));
                    let format = ImageFormat::from_path(&path).unwrap();
                    let mut file = film::AtomicFile::create(&path).unwrap();
                    film::encode(&part.image, format, &mut file).unwrap();
                    file.commit().unwrap();
                }
                part
            })
        })
        .collect();
    let parts: Vec<Rendered> = handles.into_iter().map(|t| t.join().unwrap()).collect();

    let mut joined = Image::new(w, h);
    let mut joined_png = vec![0u8; 3 * (w * h) as usize];
    let mut joined_exr = vec![(0.0f32, 0.0, 0.0); (w * h) as usize];
    for (i, (part, region)) in parts.iter().zip(regions).enumerate() {
        assert_eq!(part.region, region);
        assert_eq!((part.full_width, part.full_height), (w, h));
        assert_eq!(
            (part.image.width, part.image.height),
            (region.width, region.height)
        );
        joined.paste(region.x, region.y, &part.image);
        let png = image::open(dir.path().join(format!("part{i}.png")))
            .unwrap()
            .to_rgb8();
        assert_eq!(png.dimensions(), (region.width, region.height));
        let exr = read_exr(&dir.path().join(format!("part{i}.exr")));
        for y in 0..region.height {
            for x in 0..region.width {
                let at = ((region.y + y) * w + region.x + x) as usize;
                joined_png[3 * at..3 * at + 3].copy_from_slice(&png.get_pixel(x, y).0);
                joined_exr[at] = exr[(y * region.width + x) as usize];
            }
        }
    }
    assert_eq!(
        joined, whole.image,
        "joined film differs from the whole render"
    );
    let whole_png = image::open(dir.path().join("whole.png")).unwrap().to_rgb8();
    assert_eq!(joined_png, whole_png.into_raw(), "PNG bytes differ");
    let whole_exr = read_exr(&dir.path().join("whole.exr"));
    let bits = |v: &[(f32, f32, f32)]| -> Vec<[u32; 3]> {
        v.iter()
            .map(|p| [p.0.to_bits(), p.1.to_bits(), p.2.to_bits()])
            .collect()
    };
    assert_eq!(bits(&joined_exr), bits(&whole_exr), "EXR bits differ");
    let mut names = listing(dir.path());
    names.retain(|n| n.starts_with('.'));
    assert!(names.is_empty(), "temporary files left: {names:?}");
}

/// A region's pixels do not depend on the thread count, and a region of a study view is that
/// view's full image there too.
#[test]
fn regions_match_the_whole_image_in_every_view_and_thread_count() {
    let scene = default_heart();
    let one = Renderer::new(1).unwrap();
    let three = Renderer::new(3).unwrap();
    for &(view, _) in View::ALL {
        let request = RenderRequest {
            view,
            ..small_request()
        };
        let whole = one.render(&scene, &request, &Control::default()).unwrap();
        let region = Region {
            x: 9,
            y: 17,
            width: 40,
            height: 19,
        };
        let part = three
            .render(
                &scene,
                &RenderRequest {
                    region: Some(region),
                    ..request.clone()
                },
                &Control::default(),
            )
            .unwrap();
        assert_eq!(part.image, whole.image.crop(region), "{view}");
    }
}

/// A render that would take many seconds, cancelled after 50 ms, comes back cancelled well
/// within a second (generous: on a loaded machine one tile takes a few milliseconds).
#[test]
fn cancel_stops_a_long_render_promptly() {
    let scene = Arc::new(default_heart());
    let renderer = Arc::new(Renderer::new(2).unwrap());
    let token = CancelToken::new();
    let tiles = Arc::new(AtomicU64::new(0));
    let worker = {
        let (scene, renderer, token, tiles) = (
            Arc::clone(&scene),
            Arc::clone(&renderer),
            token.clone(),
            Arc::clone(&tiles),
        );
        std::thread::spawn(move || {
            let request = RenderRequest {
                width: Some(2000),
                height: Some(2000),
                spp: 16,
                ..RenderRequest::default()
            };
            let control = Control::new(token, move |_| {
                tiles.fetch_add(1, Ordering::Relaxed);
            });
            let result = renderer.render(&scene, &request, &control);
            (result, Instant::now())
        })
    };
    std::thread::sleep(Duration::from_millis(50));
    let cancelled_at = Instant::now();
    token.cancel();
    let (result, returned_at) = worker.join().unwrap();
    assert_eq!(result.err(), Some(RenderError::Cancelled));
    let delay = returned_at.duration_since(cancelled_at);
    assert!(delay < Duration::from_secs(1), "took {delay:?} to stop");
    // 2000×2000 is 15,625 tiles: far from all were done.
    let done = tiles.load(Ordering::Relaxed);
    println!("stopped {delay:?} after the cancel, {done} of 15625 tiles done");
    assert!(done < 15_625 / 2, "{done} tiles were rendered");
    // The same renderer still renders afterwards.
    let after = renderer.render(&scene, &small_request(), &Control::default());
    assert!(after.is_ok());
}

/// Progress is reported after every tile and reaches the region's pixel count exactly once.
#[test]
fn progress_reaches_the_total() {
    let scene = default_heart();
    let renderer = Renderer::new(2).unwrap();
    let reports = Mutex::new(Vec::<Progress>::new());
    let control = Control::new(CancelToken::new(), |p| reports.lock().unwrap().push(p));
    let region = Region {
        x: 3,
        y: 4,
        width: 50,
        height: 35,
    };
    let request = RenderRequest {
        region: Some(region),
        ..small_request()
    };
    renderer.render(&scene, &request, &control).unwrap();
    drop(control);
    let reports = reports.into_inner().unwrap();
    let total = 50 * 35;
    // 4 columns × 3 rows of tiles.
    assert_eq!(reports.len(), 12);
    assert!(reports.iter().all(|p| p.total == total));
    assert_eq!(reports.iter().map(|p| p.finished).sum::<u64>(), total);
    assert_eq!(reports.iter().filter(|p| p.done == total).count(), 1);
    assert_eq!(reports.iter().map(|p| p.done).max(), Some(total));
}

/// One loaded scene re-rendered with another camera and size gives what the scene written
/// with that camera and size gives, and the scene itself is unchanged.
#[test]
fn one_loaded_scene_re_renders_with_another_camera_and_size() {
    let scene = Arc::new(default_heart());
    let renderer = Renderer::new(2).unwrap();
    let first = renderer
        .render(&scene, &small_request(), &Control::default())
        .unwrap();
    let eye = DVec3::new(2.0, -5.0, 1.5);
    let camera = Camera::new(eye, DVec3::ZERO, DVec3::Z, 40.0).unwrap();
    let moved = RenderRequest {
        width: Some(48),
        height: None,
        camera: Some(camera),
        ..small_request()
    };
    let second = renderer
        .render(&scene, &moved, &Control::default())
        .unwrap();
    // SIZE 800 800: a lone width keeps the square aspect.
    assert_eq!((second.full_width, second.full_height), (48, 48));
    assert_eq!((scene.width, scene.height), (800, 800));

    let text = scene::DEFAULT_SCENE
        .replace("SIZE 800 800", "SIZE 48 48")
        .replace(
            "CAMERA (6, 1.2, 0.9) (0, 0, 0.05) (0, 0, 1) 32",
            "CAMERA (2, -5, 1.5) (0, 0, 0) (0, 0, 1) 40",
        );
    assert_ne!(text, scene::DEFAULT_SCENE);
    let written = scene::parse(&text, "moved.scene", &LoadOptions::default()).unwrap();
    let expected = renderer
        .render(
            &written,
            &RenderRequest {
                width: None,
                height: None,
                ..small_request()
            },
            &Control::default(),
        )
        .unwrap();
    assert_eq!(second.image, expected.image);
    // And back: the first request still gives the first image.
    let again = renderer
        .render(&scene, &small_request(), &Control::default())
        .unwrap();
    assert_eq!(again.image, first.image);
}

/// However bright the lights, the film holds finite numbers (a light built in code bypasses
/// the loader's range checks).
#[test]
fn huge_light_intensity_gives_finite_pixels() {
    let mut scene = default_heart();
    scene.lights.push(Light {
        position: DVec3::new(5.0, -2.0, 4.0),
        colour: DVec3::splat(1e308),
        radius: 0.0,
        samples: 1,
    });
    scene.lights.push(Light {
        position: DVec3::new(-3.0, 4.0, 4.0),
        colour: DVec3::new(f64::INFINITY, 1e300, 1.0),
        radius: 0.5,
        samples: 2,
    });
    let renderer = Renderer::new(2).unwrap();
    let rendered = renderer
        .render(&scene, &small_request(), &Control::default())
        .unwrap();
    let pixels = &rendered.image.pixels;
    assert!(pixels.iter().all(|p| p.is_finite()), "non-finite pixels");
    // The lights did reach the image: some channels sit at the top of the f32 range.
    assert!(pixels.iter().any(|p| p.max_element() == f32::MAX));
    let mut exr = std::io::Cursor::new(Vec::new());
    film::encode_exr(&rendered.image, true, &mut exr).unwrap();
}

/// The normals and depth views: black where nothing is hit, and what their formulas say
/// where something is.
#[test]
fn study_views_show_normals_and_depth() {
    let scene = default_heart();
    let renderer = Renderer::new(2).unwrap();
    let request = |view| RenderRequest {
        view,
        spp: 1,
        ..small_request()
    };
    let normals = renderer
        .render(&scene, &request(View::Normals), &Control::default())
        .unwrap()
        .image;
    let depth = renderer
        .render(&scene, &request(View::Depth), &Control::default())
        .unwrap()
        .image;
    let shaded = renderer
        .render(&scene, &request(View::Shaded), &Control::default())
        .unwrap()
        .image;
    assert_ne!(normals, shaded);
    // Normals: (n + 1) / 2 of unit vectors, so every channel in [0, 1] and |2c − 1| = 1.
    for p in &normals.pixels {
        let n = p.as_dvec3() * 2.0 - DVec3::ONE;
        assert!(p.min_element() >= 0.0 && p.max_element() <= 1.0);
        assert!(*p == kardia::film::Vec3::ZERO || (n.length() - 1.0).abs() < 1e-5);
    }
    // Depth: grey in (0, 1]; the floor is hit everywhere below the horizon, so the bottom
    // row is nearer (brighter) than the middle of the floor further up.
    for p in &depth.pixels {
        assert!(p.x == p.y && p.y == p.z && p.x >= 0.0 && p.x <= 1.0);
    }
    let (w, h) = (depth.width, depth.height);
    let bottom = depth.get(w / 2 - 20, h - 1).x;
    let above = depth.get(w / 2 - 20, h - 12).x;
    assert!(bottom > above && above > 0.0, "{bottom} {above}");
}

fn kardia(dir: &Path, args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_kardia"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("the kardia binary runs")
}

/// `kardia render --region` writes the region's pixels as an image of its own, equal to that
/// rectangle of the full render; `--view` selects a study view; a region outside the image
/// is an error that writes nothing.
#[test]
fn cli_renders_regions_and_views() {
    let dir = tempfile::tempdir().unwrap();
    let common = ["--width", "48", "--spp", "1", "--threads", "2", "--quiet"];
    let run = |extra: &[&str]| {
        let args: Vec<&str> = ["render"]
            .iter()
            .chain(&common)
            .chain(extra)
            .copied()
            .collect();
        let out = kardia(dir.path(), &args);
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    };
    run(&["-o", "whole.png"]);
    run(&["-o", "part.png", "--region", "5,10,30,20"]);
    run(&["-o", "normals.png", "--view", "normals"]);
    let whole = image::open(dir.path().join("whole.png")).unwrap().to_rgb8();
    let part = image::open(dir.path().join("part.png")).unwrap().to_rgb8();
    assert_eq!(part.dimensions(), (30, 20));
    for y in 0..20 {
        for x in 0..30 {
            assert_eq!(part.get_pixel(x, y), whole.get_pixel(x + 5, y + 10));
        }
    }
    let normals = image::open(dir.path().join("normals.png"))
        .unwrap()
        .to_rgb8();
    assert_eq!(normals.dimensions(), whole.dimensions());
    assert_ne!(normals, whole);

    let args = [
        "render", "--width", "48", "--region", "40,0,9,9", "-o", "x.png",
    ];
    let out = kardia(dir.path(), &args);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("does not lie inside the 48×48 image"), "{err}");
    assert_eq!(
        listing(dir.path()),
        ["normals.png", "part.png", "whole.png"]
    );
}

/// `max_shadow_rays` caps each spherical light's shadow rays per sample (the explorer's live
/// view takes 1); without it the scene's `SAMPLES` hold, and the cap changes nothing for a
/// light that has fewer.
#[test]
fn shadow_rays_per_light_can_be_capped_for_previews() {
    let scene = default_heart(); // a spherical light with SAMPLES 4, and a point light
    let renderer = Renderer::new(2).unwrap();
    let render = |cap: Option<u32>| {
        let request = RenderRequest {
            width: Some(48),
            height: Some(48),
            spp: 2,
            max_shadow_rays: cap,
            ..RenderRequest::default()
        };
        renderer
            .render(&scene, &request, &Control::default())
            .unwrap()
    };
    let full = render(None);
    let same = render(Some(4));
    let preview = render(Some(1));
    assert_eq!(full.image.to_srgb8(), same.image.to_srgb8());
    assert_eq!(full.stats.rays, same.stats.rays);
    assert!(
        preview.stats.rays * 10 < full.stats.rays * 7,
        "{} vs {}",
        preview.stats.rays,
        full.stats.rays
    );
    // Same picture up to the soft shadows' noise: the mean colour within 2 %.
    let mean = |r: &Rendered| {
        let v = r.image.to_srgb8();
        v.iter().map(|&c| c as f64).sum::<f64>() / v.len() as f64
    };
    let (a, b) = (mean(&full), mean(&preview));
    assert!((a - b).abs() < 0.02 * a, "{a} vs {b}");
}

/// Two renders on one `Renderer` share its threads band by band: a small render started
/// while a long one runs finishes long before it (before the fix, it waited for the whole
/// long render, as a page's coarse frame waited for another page's refinement pass).
#[test]
fn a_small_render_does_not_wait_for_a_long_one_on_the_same_renderer() {
    let scene = Arc::new(default_heart());
    let renderer = Arc::new(Renderer::new(2).unwrap());
    let long_done = Arc::new(Mutex::new(None::<Instant>));
    let started = Arc::new(AtomicU64::new(0));
    let long = {
        let (scene, renderer, long_done, started) = (
            scene.clone(),
            renderer.clone(),
            long_done.clone(),
            started.clone(),
        );
        std::thread::spawn(move || {
            let request = RenderRequest {
                width: Some(192),
                height: Some(192),
                spp: 48,
                ..RenderRequest::default()
            };
            let progress = move |_: Progress| {
                started.store(1, Ordering::Relaxed);
            };
            let control = Control {
                progress: Box::new(progress),
                ..Control::default()
            };
            renderer.render(&scene, &request, &control).unwrap();
            *long_done.lock().unwrap() = Some(Instant::now());
        })
    };
    while started.load(Ordering::Relaxed) == 0 {
        std::thread::sleep(Duration::from_millis(1));
    }
    let small = RenderRequest {
        width: Some(32),
        height: Some(32),
        spp: 1,
        ..RenderRequest::default()
    };
    renderer
        .render(&scene, &small, &Control::default())
        .unwrap();
    let small_done = Instant::now();
    assert!(
        long_done.lock().unwrap().is_none(),
        "the small render waited for the long one"
    );
    long.join().unwrap();
    assert!(long_done.lock().unwrap().unwrap() > small_done);
}

/// An interactive render goes ahead of a batch render already running on the same
/// `Renderer`: from the interactive render's first finished tile to its last, the batch render
/// finishes no more than the tile each of its threads was in when the interactive render was
/// counted in (it hands the threads over within a few pixels), and the batch render, suspended
/// and resumed many times, still makes exactly the pixels and bands it makes alone (kept and
/// streamed). Before the priority, the two shared the threads band by band: a 12-band
/// interactive render let the batch render finish a band of 12 tiles before each of its own.
///
/// The window is read from the interactive render's own progress, not from around the call:
/// on a loaded machine the test's thread can be held between reading the batch's count and the
/// render counting itself in (or after it ends) while the batch render goes on, as it should.
#[test]
fn an_interactive_render_goes_ahead_of_a_batch_render() {
    let scene = Arc::new(default_heart());
    let renderer = Arc::new(Renderer::new(2).unwrap());
    let batch = RenderRequest {
        width: Some(160),
        height: Some(120),
        spp: 24,
        seed: 9,
        ..RenderRequest::default()
    };
    let alone = renderer
        .render(&scene, &batch, &Control::default())
        .unwrap();
    let interactive = RenderRequest {
        width: Some(48),
        height: Some(192),
        spp: 4,
        ..RenderRequest::default()
    };
    for streamed in [false, true] {
        let tiles = Arc::new(AtomicU64::new(0));
        let finished = Arc::new(AtomicU64::new(0));
        let bands = Arc::new(Mutex::new(vec![None::<Vec<film::Vec3>>; 8]));
        let long = {
            let (scene, renderer, batch) = (scene.clone(), renderer.clone(), batch.clone());
            let (tiles, finished, bands) = (tiles.clone(), finished.clone(), bands.clone());
            std::thread::spawn(move || {
                let progress = move |_: Progress| {
                    tiles.fetch_add(1, Ordering::SeqCst);
                };
                let control = Control::new(CancelToken::new(), progress);
                let hook = |row: u32, rows: &[film::Vec3], _: Option<&[f32]>| {
                    bands.lock().unwrap()[row as usize / 16] = Some(rows.to_vec());
                };
                let image = if streamed {
                    renderer
                        .render_streamed(&scene, &batch, &control, &hook)
                        .map(|_| None)
                } else {
                    renderer
                        .render_in_bands(&scene, &batch, &control, &hook)
                        .map(|r| Some(r.image))
                };
                finished.store(1, Ordering::SeqCst);
                image.unwrap()
            })
        };
        while tiles.load(Ordering::SeqCst) == 0 {
            std::thread::sleep(Duration::from_millis(1));
        }
        let mut most_during = 0;
        let mut runs = 0;
        while finished.load(Ordering::SeqCst) == 0 && runs < 40 {
            // The batch's finished tiles at the interactive render's first and last tile.
            let window = Arc::new(Mutex::new((None::<u64>, None::<u64>)));
            let progress = {
                let (tiles, window) = (tiles.clone(), window.clone());
                move |p: Progress| {
                    let now = tiles.load(Ordering::SeqCst);
                    let mut window = window.lock().unwrap();
                    window.0.get_or_insert(now);
                    if p.done == p.total {
                        window.1 = Some(now);
                    }
                }
            };
            let control =
                Control::new(CancelToken::new(), progress).with_priority(Priority::Interactive);
            renderer.render(&scene, &interactive, &control).unwrap();
            let (Some(first), Some(last)) = *window.lock().unwrap() else {
                panic!("the interactive render reported no progress");
            };
            most_during = most_during.max(last - first);
            runs += 1;
            std::thread::sleep(Duration::from_millis(3));
        }
        let image = long.join().unwrap();
        assert!(
            runs >= 3,
            "only {runs} interactive renders ran during the batch render"
        );
        // Each of the two threads may finish the tile it was in when the interactive render
        // was counted in; none starts another while it runs.
        assert!(
            most_during <= 2,
            "the batch render finished {most_during} tiles during one interactive render"
        );
        if let Some(image) = image {
            assert_eq!(image.pixels, alone.image.pixels, "kept");
        }
        let bands = bands.lock().unwrap();
        for (band, rows) in alone.image.pixels.chunks(160 * 16).zip(bands.iter()) {
            assert_eq!(Some(band), rows.as_deref(), "streamed {streamed}");
        }
    }
}
