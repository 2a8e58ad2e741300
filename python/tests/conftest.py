"""Shared fixtures: the kardia command line to compare against, and small scenes.

The CLI binary is `$KARDIA_BIN`, else the repository's target/debug/kardia (what `cargo test`
builds) or target/release/kardia. Without one, the tests that compare with it fail in CI
(CI=true) and skip with a loud message elsewhere.
"""

import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]

# A small scene of its own: the heart over a floor, a sphere beside it, at 48×40.
SMALL_SCENE = """\
SIZE 48 40
CAMERA (6, 1.2, 0.9) (0, 0, 0.05) (0, 0, 1) 32
BACKGROUND (0.03, 0.03, 0.05)
AMBIENT (0.06, 0.05, 0.06)
LIGHT (7, -4, 6) (0.9, 0.88, 0.85) 0.6 SAMPLES 2
HEART (0, 0, 0) (1, 0, 0) (0, 1, 0) (0, 0, 1) (0.75, 0.04, 0.08) SPECULAR 0.6 80
SPHERE (0, 1.6, -0.5) 0.4 (0.2, 0.4, 0.8) REFLECT 0.3
PLANE (0, 0, -1.05) (0, 0, 1) (0.5, 0.5, 0.55) REFLECT 0.15
"""

# An animation of its own: 4 frames, the heart grows and the light moves with the frame.
ANIMATED_SCENE = """\
SIZE 40 32
FRAMES 4
LET s = 0.8 + 0.1*frame
CAMERA (6, 1.2, 0.9) (0, 0, 0.05) (0, 0, 1) 32
BACKGROUND (0.03, 0.03, 0.05)
LIGHT (7, -4 + frame, 6) (0.9, 0.88, 0.85) 0.6 SAMPLES 2
HEART (0, 0, 0) (s, 0, 0) (0, s, 0) (0, 0, s) (0.75, 0.04, 0.08)
PLANE (0, 0, -1.05) (0, 0, 1) (0.5, 0.5, 0.55)
"""


def _find_cli():
    given = os.environ.get("KARDIA_BIN")
    if given:
        return pathlib.Path(given)
    for profile in ("debug", "release"):
        path = REPO / "target" / profile / "kardia"
        if path.is_file():
            return path
    return None


@pytest.fixture(scope="session")
def cli():
    """A function running the kardia CLI with arguments; returns the completed process."""
    path = _find_cli()
    if path is None or not path.is_file():
        message = (
            "NO KARDIA BINARY: build it with `cargo build` (or set KARDIA_BIN); "
            "the tests comparing with the command line did not run"
        )
        if os.environ.get("CI"):
            pytest.fail(message)
        print(f"\n!!!!! {message} !!!!!", file=sys.stderr)
        pytest.skip(message)

    def run(*args, input=None, check=True):
        done = subprocess.run(
            [str(path), *map(str, args)], input=input, capture_output=True, text=True
        )
        if check and done.returncode != 0:
            raise AssertionError(f"kardia {' '.join(map(str, args))} failed:\n{done.stderr}")
        return done

    return run


def read_png(path):
    """The PNG at `path` as a uint8 array (H, W, channels), decoded by Pillow."""
    from PIL import Image

    with Image.open(path) as im:
        return np.asarray(im).copy()


@pytest.fixture
def small_scene_file(tmp_path):
    path = tmp_path / "small.scene"
    path.write_text(SMALL_SCENE)
    return path


@pytest.fixture
def animated_scene_file(tmp_path):
    path = tmp_path / "animated.scene"
    path.write_text(ANIMATED_SCENE)
    return path


def need(module):
    """`module` imported: in CI (CI set) it must be there; elsewhere a test without it skips
    with a loud message."""
    import importlib

    if os.environ.get("CI"):
        return importlib.import_module(module)
    try:
        return importlib.import_module(module)
    except ImportError:
        print(f"\n!!!!! {module} is not installed: this test did not run !!!!!", file=sys.stderr)
        pytest.skip(f"{module} is not installed", allow_module_level=True)
