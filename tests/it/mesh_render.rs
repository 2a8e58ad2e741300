//! `MESH` renders `kardia mesh`'s output back: the silhouettes of the mesh and of the exact
//! surface, seen from two cameras, agree to within a pixel, and a wrongly placed mesh does
//! not pass the same test. The meshes are written by the library's writers in every format
//! the `MESH` primitive reads and loaded through the scene language.

use kardia::camera::Camera;
use kardia::geometry::DVec3;
use kardia::mesh::write::{write_file, MeshFormat, MeshMetadata};
use kardia::mesh::{self, MeshRequest, SolidKind};
use kardia::scene::{self, LoadOptions, Scene};
use std::path::Path;

const N: u32 = 120;

fn scene(text: &str) -> Scene {
    scene::parse(text, "mesh_render", &LoadOptions::default()).unwrap_or_else(|e| panic!("{e:?}"))
}

/// Which pixels of an N×N image see the scene's first object.
fn silhouette(scene: &Scene, cam: &Camera) -> Vec<bool> {
    let shape = &scene.objects[0].shape;
    (0..N * N)
        .map(|i| {
            let ray = cam.ray((i % N) as f64 + 0.5, (i / N) as f64 + 0.5, N, N);
            shape.intersect(&ray, 1e-9, f64::INFINITY).is_some()
        })
        .collect()
}

/// The pixels where the two silhouettes differ, and those of them with no pixel of the
/// other kind in `exact` within `reach` pixels (not on the exact silhouette's outline).
fn disagreement(exact: &[bool], other: &[bool], reach: i64) -> (usize, usize) {
    let n = N as i64;
    let at = |x: i64, y: i64| exact[(x.clamp(0, n - 1) + n * y.clamp(0, n - 1)) as usize];
    let mut differ = 0;
    let mut off_outline = 0;
    for y in 0..n {
        for x in 0..n {
            let i = (x + n * y) as usize;
            if exact[i] == other[i] {
                continue;
            }
            differ += 1;
            let near_edge = (-reach..=reach)
                .any(|dy| (-reach..=reach).any(|dx| at(x + dx, y + dy) != exact[i]));
            if !near_edge {
                off_outline += 1;
            }
        }
    }
    (differ, off_outline)
}

/// Meshes the first object of `exact_text` with `kardia mesh`'s library path, writes it as
/// `format` into `dir`, and returns the file.
fn mesh_file(exact_text: &str, format: &str, dir: &Path) -> std::path::PathBuf {
    let solids = mesh::scene_solids(&scene(exact_text));
    let request = MeshRequest {
        kind: SolidKind::Inside,
        tolerance: Some(0.01),
        ..MeshRequest::default()
    };
    let printable = mesh::mesh_solids(&solids, &request, None, &|_, _, _| {}).unwrap();
    let path = dir.join(format!("mesh.{format}"));
    let meta = MeshMetadata {
        name: "test".into(),
        colour: [200, 100, 50],
        millimetres: false,
    };
    write_file(
        &printable.mesh,
        &meta,
        MeshFormat::from_path(&path).unwrap(),
        &path,
    )
    .unwrap();
    path
}

#[test]
fn meshes_render_back_with_the_exact_silhouette_from_two_cameras() {
    let dir = tempfile::tempdir().unwrap();
    let cameras = [
        Camera::new(DVec3::new(6.0, 1.2, 0.9), DVec3::ZERO, DVec3::Z, 30.0).unwrap(),
        Camera::new(DVec3::new(-2.0, -4.0, 4.5), DVec3::ZERO, DVec3::Z, 30.0).unwrap(),
    ];
    let cases = [
        (
            "HEART (0, 0.1, 0) (1, 0, 0) (0, 1, 0) (0, 0, 1) (1, 0, 0)",
            "stl",
        ),
        (
            "IMPLICIT \"x^4 + y^4 + z^4 - (x^2 + y^2 + z^2) = 0.2\" (0, 0, 0) (0.9, 0, 0.3) \
             (0, 1, 0) (0, 0, 1) (1, 0, 0)",
            "ply",
        ),
        (
            "IMPLICIT torus 1 0.35 (0, 0, 0) (1, 0, 0) (0, 1, 0) (0, 0, 1) (1, 0, 0)",
            "obj",
        ),
    ];
    for (object, format) in cases {
        let camera_line = "CAMERA (6, 0, 0) (0, 0, 0) (0, 0, 1) 30\n";
        let exact = scene(&format!("{camera_line}{object}\n"));
        let file = mesh_file(&format!("{camera_line}{object}\n"), format, dir.path());
        let placed = |frame: &str, normals: &str| {
            scene(&format!(
                "{camera_line}MESH \"{}\" {frame} (0.2, 0.5, 0.9) {normals}\n",
                file.display()
            ))
        };
        let same = "(0, 0, 0) (1, 0, 0) (0, 1, 0) (0, 0, 1)";
        // Moved by two pixels' width, and 4% larger.
        let wrong = [
            "(0, 0.05, 0.05) (1, 0, 0) (0, 1, 0) (0, 0, 1)",
            "(0, 0, 0) (1.04, 0, 0) (0, 1.04, 0) (0, 0, 1.04)",
        ];
        for cam in &cameras {
            let want = silhouette(&exact, cam);
            let seen = want.iter().filter(|&&b| b).count();
            assert!(seen > 400, "{object}: {seen} pixels");
            for normals in ["SMOOTH", "FLAT"] {
                let got = silhouette(&placed(same, normals), cam);
                let (differ, off) = disagreement(&want, &got, 1);
                // Within a pixel of the outline, and few even there.
                assert_eq!(
                    off, 0,
                    "{object} {format}: {differ} differ, {off} off the outline"
                );
                assert!(
                    differ * 20 <= seen,
                    "{object} {format}: {differ} of {seen} differ"
                );
            }
            for frame in wrong {
                let got = silhouette(&placed(frame, "SMOOTH"), cam);
                let (differ, off) = disagreement(&want, &got, 1);
                assert!(
                    off > 0 || differ * 20 > seen,
                    "{object}: a wrong placement {frame} passed ({differ} differ)"
                );
            }
        }
    }
}

#[test]
fn a_mesh_file_that_cannot_be_read_is_an_error_at_its_name() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.stl");
    let bad = dir.path().join("bad.obj");
    std::fs::write(&bad, "v 0 0 0\nf 1 2 3\n").unwrap();
    for (file, says) in [
        (missing.display().to_string(), "cannot read the mesh file"),
        (bad.display().to_string(), "not among"),
        ("mesh.xyz".to_string(), "unknown mesh format"),
    ] {
        let text = format!(
            "CAMERA (6, 0, 0) (0, 0, 0) (0, 0, 1) 30\nMESH \"{file}\" (0, 0, 0) (1, 0, 0) \
             (0, 1, 0) (0, 0, 1) (1, 1, 1)\n"
        );
        let e = scene::parse(&text, "t", &LoadOptions::default()).unwrap_err();
        let message = format!("{e:?}");
        assert!(message.contains(says), "{message}");
    }
}

/// An ASCII STL of the tetrahedron with corners at the origin and at `s` on each axis.
fn tetrahedron_stl(s: f64) -> String {
    let corners = [[0.0, 0.0, 0.0], [s, 0.0, 0.0], [0.0, s, 0.0], [0.0, 0.0, s]];
    let mut text = String::from("solid t\n");
    for [a, b, c] in [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]] {
        text.push_str("facet normal 0 0 0\nouter loop\n");
        for k in [a, b, c] {
            let [x, y, z] = corners[k];
            text.push_str(&format!("vertex {x} {y} {z}\n"));
        }
        text.push_str("endloop\nendfacet\n");
    }
    text + "endsolid t\n"
}

#[test]
fn a_changed_mesh_file_is_a_new_render_for_resume() {
    // The scene text stays the same; the MESH file it names changes: the render key (what
    // `--resume` compares) must change with it, and only with it.
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(
        d.join("t.scene"),
        "SIZE 24 20\nCAMERA (3, 2, 1.5) (0.3, 0.3, 0.3) (0, 0, 1) 40\nLIGHT (5, 5, 5) (1, 1, 1)\n\
         MESH \"t.stl\" (0, 0, 0) (1, 0, 0) (0, 1, 0) (0, 0, 1) (0.8, 0.3, 0.2)\n",
    )
    .unwrap();
    let render = |out: &str, resume: bool| {
        let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_kardia"));
        c.current_dir(d)
            .args(["render", "t.scene", "--spp", "1", "-o", out]);
        if resume {
            c.arg("--resume");
        }
        let o = c.output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stderr).to_string()
    };
    let key = |name: &str| kardia::film::read_tag(&d.join(name), kardia::tiles::KEY_TAG).unwrap();
    std::fs::write(d.join("t.stl"), tetrahedron_stl(1.0)).unwrap();
    render("a.png", false);
    render("same.png", false);
    assert_eq!(key("a.png"), key("same.png"), "the same file, the same key");
    let first = std::fs::read(d.join("a.png")).unwrap();
    std::fs::write(d.join("t.stl"), tetrahedron_stl(0.5)).unwrap();
    render("b.png", false);
    assert_ne!(key("a.png"), key("b.png"), "a changed file, a new key");
    // --resume redoes the frame made from the old file.
    render("a.png", true);
    assert_eq!(key("a.png"), key("b.png"));
    assert_ne!(std::fs::read(d.join("a.png")).unwrap(), first);
}
