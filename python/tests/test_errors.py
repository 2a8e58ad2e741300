"""Bad scenes and bad arguments raise clear exceptions and never crash the interpreter."""

import numpy as np
import pytest

import kardia
from conftest import SMALL_SCENE

BAD = "SIZE 10 10\nSPHERE (0,0,0) x\n"


def test_scene_errors_carry_the_cli_report(cli, tmp_path):
    path = tmp_path / "bad.scene"
    path.write_text(BAD)
    with pytest.raises(kardia.SceneError) as caught:
        kardia.Scene.from_file(path)
    e = caught.value
    assert isinstance(e, ValueError)
    assert (e.file, e.line, e.column) == (str(path), 2, 16)
    assert e.message.startswith("expected the sphere's radius")
    report = cli("render", path, "-o", tmp_path / "x.png", check=False).stderr
    assert str(e) == report.rstrip()
    assert f"{path}:2:16" in str(e) and "SPHERE (0,0,0) x" in str(e)


def test_scene_text_errors_name_the_given_name():
    with pytest.raises(kardia.SceneError, match=r"mine\.scene:2:16") as caught:
        kardia.Scene(BAD, "mine.scene")
    assert caught.value.line == 2
    with pytest.raises(kardia.SceneError, match="cannot read scene file") as caught:
        kardia.Scene.from_file("/nonexistent/nothing.scene")
    assert caught.value.line is None


@pytest.mark.parametrize(
    "kwargs, error",
    [
        (dict(width=-1), ValueError),
        (dict(width=0), ValueError),
        (dict(height=10**9), ValueError),
        (dict(samples=0), ValueError),
        (dict(samples=-3), ValueError),
        (dict(seed=-1), ValueError),
        (dict(threads=0), ValueError),
        (dict(max_depth=-1), ValueError),
        (dict(view="nope"), ValueError),
        (dict(width="wide"), TypeError),
        (dict(samples=1.5), TypeError),
        (dict(region=(0, 0, 100, 10)), ValueError),
        (dict(region=(0, 0, 0, 10)), ValueError),
        (dict(tile=(3, 3)), ValueError),
        (dict(tile=(0, 1000)), ValueError),
        (dict(region=(0, 0, 4, 4), alpha=True), ValueError),
        (dict(frame=1), ValueError),
        (dict(frame=-1), ValueError),
        (dict(turntable=0, frame=0), ValueError),
        (dict(camera="front"), TypeError),
    ],
)
def test_bad_render_arguments(kwargs, error):
    with pytest.raises(error):
        kardia.Scene(SMALL_SCENE).render(**kwargs)


def test_bad_cameras():
    with pytest.raises(ValueError):
        kardia.Camera((0, 0, 0), (0, 0, 0))
    with pytest.raises(ValueError):
        kardia.Camera((1, 0, 0), (0, 0, 0), fov=200)
    with pytest.raises(ValueError):
        kardia.Camera((float("nan"), 0, 0), (0, 0, 0))
    with pytest.raises(ValueError):
        kardia.Camera((0, 0, 5), (0, 0, 0), up=(0, 0, 1))


def test_bad_probes():
    scene = kardia.Scene(SMALL_SCENE)
    with pytest.raises(ValueError, match=r"shape \(N, 3\)"):
        scene.probe(np.zeros((4, 2)), np.ones((4, 2)))
    with pytest.raises(ValueError, match=r"shape \(N, 3\)"):
        scene.probe(np.zeros((4, 3)), np.ones((5, 3)))
    with pytest.raises(ValueError, match="ray 1: the direction .* not finite"):
        scene.probe(np.zeros((2, 3)), [[1, 0, 0], [np.nan, 0, 0]])
    with pytest.raises(ValueError, match="ray 0: the direction must not be zero"):
        scene.probe([[0, 0, 0]], [[0, 0, 0]])
    with pytest.raises(ValueError, match="outside the valid range"):
        scene.probe([[2e6, 0, 0]], [[1, 0, 0]])
    with pytest.raises(ValueError):
        scene.probe([["a", "b", "c"]], [[1, 0, 0]])


def test_bad_roots_and_meshes():
    for coeffs, interval in [([], (0, 1)), ([1] * 18, (0, 1)), ([1, np.nan], (0, 1)),
                             ([1, 2], (1, 0)), ([1, 2], (np.nan, 1)), ([[1, 2]], (0, 1))]:
        with pytest.raises(ValueError):
            kardia.roots(coeffs, interval)
    with pytest.raises(ValueError, match="solver"):
        kardia.roots([1, 2], (0, 1), first=True, solver="newton")
    with pytest.raises(ValueError, match="nothing to mesh"):
        kardia.Scene("CAMERA (5,0,0) (0,0,0) (0,0,1) 40\nSPHERE (0,0,0) 1 (1,1,1)\n").mesh()
    with pytest.raises(ValueError):
        kardia.Scene.heart().mesh("sideways")
    with pytest.raises(ValueError):
        kardia.Scene.heart().mesh(tolerance=-1)
