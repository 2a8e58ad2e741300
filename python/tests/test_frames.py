"""Frames and turntables: each frame what `kardia render --frame N` makes."""

import numpy as np

import kardia
from conftest import read_png


def test_frames_equal_the_cli_frames(cli, animated_scene_file, tmp_path):
    scene = kardia.Scene.from_file(animated_scene_file)
    assert scene.declared_frames == 4 and scene.frame_count() == 4 and scene.animated
    frames = list(scene.frames())
    assert [f.frame for f in frames] == [0, 1, 2, 3]
    for n, image in enumerate(frames):
        out = tmp_path / f"cli_{n}.png"
        cli("render", animated_scene_file, "--frame", n, "-o", out, "--quiet")
        np.testing.assert_array_equal(image.array, read_png(out))
        mine = tmp_path / f"py_{n}.png"
        image.save(mine)
        assert mine.read_bytes() == out.read_bytes()
    assert not np.array_equal(frames[0].array, frames[3].array)
    assert [f.frame for f in scene.frames([2, 0])] == [2, 0]


def test_turntable_frames_equal_the_cli(cli, small_scene_file, tmp_path):
    scene = kardia.Scene.from_file(small_scene_file)
    assert scene.frame_count(turntable=6) == 6
    out = tmp_path / "turn_3.png"
    cli("render", small_scene_file, "--turntable", 6, "--frame", 3, "-o", out, "--quiet")
    image = scene.render(frame=3, turntable=6)
    mine = tmp_path / "py_3.png"
    image.save(mine)
    assert mine.read_bytes() == out.read_bytes()
    assert len(list(scene.frames(turntable=3, samples=1, width=16))) == 3


def test_tiles_and_regions_are_the_cli_parts(cli, small_scene_file, tmp_path):
    scene = kardia.Scene.from_file(small_scene_file)
    whole = scene.render().array
    bands = [scene.render(tile=(i, 3)) for i in range(3)]
    np.testing.assert_array_equal(np.concatenate([b.array for b in bands]), whole)
    for i, band in enumerate(bands):
        out = tmp_path / f"cli_tile{i}.png"
        cli("render", small_scene_file, "--tile", f"{i}/3", "-o", out, "--quiet")
        mine = tmp_path / f"py_tile{i}.png"
        band.save(mine)
        assert mine.read_bytes() == out.read_bytes()
    # The parts the Python side wrote join (by `kardia assemble`) into the CLI's whole image.
    cli("render", small_scene_file, "-o", tmp_path / "whole.png", "--quiet")
    cli("assemble", *[tmp_path / f"py_tile{i}.png" for i in range(3)], "-o", tmp_path / "joined.png")
    assert (tmp_path / "joined.png").read_bytes() == (tmp_path / "whole.png").read_bytes()


def test_frame_paths():
    assert kardia.frame_path("out/heart_####.png", 7) == "out/heart_0007.png"
    assert kardia.frame_path("heart_##.png", 123) == "heart_123.png"
