"""Renders from Python against the kardia command line: the same pixels, the same files."""

import pickle

import numpy as np
import pytest

import kardia
from conftest import SMALL_SCENE, read_png


def test_array_equals_the_cli_pixels(cli, small_scene_file, tmp_path):
    out = tmp_path / "cli.png"
    cli("render", small_scene_file, "-o", out, "--spp", 3, "--seed", 7, "--quiet")
    image = kardia.Scene.from_file(small_scene_file).render(samples=3, seed=7)
    expected = read_png(out)
    assert image.array.dtype == np.uint8
    assert image.array.shape == expected.shape == (40, 48, 3)
    np.testing.assert_array_equal(image.array, expected)
    # Another seed changes the pixels: the comparison can fail.
    other = kardia.Scene.from_file(small_scene_file).render(samples=3, seed=8)
    assert not np.array_equal(other.array, expected)


def test_saved_files_are_the_cli_files_byte_for_byte(cli, small_scene_file, tmp_path):
    scene = kardia.Scene.from_file(small_scene_file)
    for name, extra in [("a.png", []), ("b.exr", []), ("c.exr", ["--half"]), ("d.png", ["--alpha"])]:
        out = tmp_path / f"cli_{name}"
        cli("render", small_scene_file, "-o", out, "--width", 40, "--quiet", *extra)
        mine = tmp_path / f"py_{name}"
        scene.render(width=40, alpha="--alpha" in extra).save(mine, half="--half" in extra)
        assert mine.read_bytes() == out.read_bytes(), name


def test_every_view_equals_the_cli(cli, small_scene_file, tmp_path):
    scene = kardia.Scene.from_file(small_scene_file)
    assert set(kardia.VIEWS) >= {"shaded", "normals", "depth", "roots", "path", "iterations", "conditioning"}
    for view in kardia.VIEWS:
        out = tmp_path / f"{view}.png"
        cli("render", small_scene_file, "-o", out, "--view", view, "--spp", 1, "--quiet")
        array = scene.render(view=view, samples=1).array
        np.testing.assert_array_equal(array, read_png(out), err_msg=view)


def test_alpha_is_straight_rgba_as_the_cli_writes(cli, small_scene_file, tmp_path):
    out = tmp_path / "alpha.png"
    cli("render", small_scene_file, "-o", out, "--alpha", "--quiet")
    image = kardia.Scene.from_file(small_scene_file).render(alpha=True)
    assert image.array.shape == (40, 48, 4) and image.alpha
    np.testing.assert_array_equal(image.array, read_png(out))


def test_default_heart_equals_kardia_render_without_a_scene(cli, tmp_path):
    out = tmp_path / "heart.png"
    cli("render", "-o", out, "--width", 64, "--spp", 1, "--quiet")
    array = kardia.Scene.heart().render(width=64, samples=1).array
    np.testing.assert_array_equal(array, read_png(out))


def test_a_camera_override_is_the_scene_with_that_camera():
    camera = kardia.Camera((5, -3, 2), (0, 0, 0), (0, 0, 1), 35)
    moved = SMALL_SCENE.replace(
        "CAMERA (6, 1.2, 0.9) (0, 0, 0.05) (0, 0, 1) 32", "CAMERA (5, -3, 2) (0, 0, 0) (0, 0, 1) 35"
    )
    assert moved != SMALL_SCENE
    a = kardia.Scene(SMALL_SCENE).render(camera=camera).array
    b = kardia.Scene(moved).render().array
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, kardia.Scene(SMALL_SCENE).render().array)


def test_dtypes_and_shapes():
    scene = kardia.Scene(SMALL_SCENE)
    assert scene.size == (48, 40)
    srgb = scene.render(samples=1)
    assert (srgb.width, srgb.height) == (48, 40)
    assert srgb.array.shape == (40, 48, 3) and srgb.array.dtype == np.uint8
    linear = scene.render(samples=1, linear=True)
    assert linear.array.shape == (40, 48, 3) and linear.array.dtype == np.float32
    # The same pixels: sRGB-encoding the linear values gives the uint8 array (within the
    # rounding of this approximate formula).
    lin = np.clip(linear.array.astype(np.float64), 0, 1)
    encoded = np.where(lin <= 0.0031308, 12.92 * lin, 1.055 * lin ** (1 / 2.4) - 0.055)
    assert np.abs(np.round(encoded * 255) - srgb.array).max() <= 1
    np.testing.assert_array_equal(linear.to_array(), srgb.array)
    rgba = scene.render(samples=1, alpha=True, linear=True)
    assert rgba.array.shape == (40, 48, 4) and rgba.array.dtype == np.float32
    assert 0.0 <= rgba.array[..., 3].min() and rgba.array[..., 3].max() <= 1.0
    assert scene.render(width=24, samples=1).array.shape == (20, 24, 3)  # keeps the aspect
    assert scene.render(width=10, height=30, samples=1).array.shape == (30, 10, 3)
    part = scene.render(region=(4, 8, 16, 12), samples=1)
    assert part.array.shape == (12, 16, 3) and part.region == (4, 8, 16, 12)
    np.testing.assert_array_equal(part.array, srgb.array[8:20, 4:20])
    assert np.asarray(srgb).shape == (40, 48, 3)
    assert np.asarray(srgb, dtype=np.float64).dtype == np.float64


def test_row_zero_is_the_top():
    # A floor seen from above the horizon fills the bottom, not the top.
    scene = kardia.Scene(
        "SIZE 16 16\nCAMERA (0, -5, 1) (0, 0, 1) (0, 0, 1) 60\nBACKGROUND (0, 0, 0)\n"
        "AMBIENT (1, 1, 1)\nPLANE (0, 0, 0) (0, 0, 1) (1, 1, 1)\n"
    )
    a = scene.render(samples=1).array
    assert a[0].max() == 0 and a[-1].min() > 0


def test_png_repr_and_pickling():
    scene = kardia.Scene(SMALL_SCENE, "small")
    png = scene.render(width=16, samples=1)._repr_png_()
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    again = pickle.loads(pickle.dumps(scene))
    assert again.text == scene.text and again.name == "small"
    np.testing.assert_array_equal(again.render(samples=1).array, scene.render(samples=1).array)


def test_equations_and_presets_make_scenes():
    sphere = kardia.Scene.from_equation("x^2 + y^2 + z^2 = 1", bound=1.5, size=(32, 32))
    assert sphere.objects == [("IMPLICIT", 7)]
    hit = sphere.probe([[6, 0, 0]], [[-1, 0, 0]])
    assert hit["hit"][0] and abs(hit["t"][0] - 5.0) < 1e-12
    torus = kardia.Scene.from_preset("torus", 1, 0.3, scale=0.5, colour=(0.1, 0.8, 0.2), size=(32, 24))
    assert "IMPLICIT torus 1.0 0.3" in torus.text and torus.size == (32, 24)
    hit = torus.probe([[6, 0, 0]], [[-1, 0, 0]])
    assert abs(hit["t"][0] - (6 - 0.5 * 1.3)) < 1e-9
    ortho = kardia.Camera((0, 0, 10), (0, 0, 0), (0, 1, 0), orthographic_height=3)
    assert "ORTHOGRAPHIC 3.0" in kardia.Scene.from_equation("x^2+y^2+z^2-1", camera=ortho).text
    image = torus.render(samples=1)
    assert image.array.shape == (24, 32, 3) and image.array.any()


def test_progress_reaches_the_total():
    seen = []
    kardia.Scene(SMALL_SCENE).render(samples=1, progress=lambda done, total: seen.append((done, total)))
    assert seen and seen[-1] == (48 * 40, 48 * 40)
    assert all(a[0] <= b[0] for a, b in zip(seen, seen[1:]))
    # progress=True uses tqdm when it is installed, and renders the same either way.
    kardia.Scene(SMALL_SCENE).render(samples=1, progress=True)


def test_a_failing_progress_callback_stops_the_render():
    def boom(done, total):
        raise RuntimeError("stop here")

    with pytest.raises(RuntimeError, match="stop here"):
        kardia.Scene(SMALL_SCENE).render(width=400, samples=16, progress=boom)
