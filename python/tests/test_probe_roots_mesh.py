"""Probes, roots and meshes against the command line and known answers."""

import json

import numpy as np
import pytest

import kardia
from conftest import need


def test_probe_equals_kardia_probe(cli, small_scene_file):
    rng = np.random.default_rng(3)
    origins = np.tile([6.0, 1.2, 0.9], (40, 1)) + rng.normal(scale=0.2, size=(40, 3))
    directions = -origins + rng.normal(scale=0.4, size=(40, 3))
    directions[::4] = [0.3, 0.2, 1.0]  # up into the sky: misses
    result = kardia.Scene.from_file(small_scene_file).probe(origins, directions)
    lines = "\n".join(" ".join(repr(float(x)) for x in np.r_[o, d]) for o, d in zip(origins, directions))
    answers = [json.loads(l) for l in cli("probe", small_scene_file, input=lines + "\n").stdout.splitlines()]
    assert len(answers) == 40
    keywords = [k for k, _ in kardia.Scene.from_file(small_scene_file).objects]
    assert result["hit"].dtype == bool and result["t"].shape == (40,)
    assert result["point"].shape == (40, 3) and result["object"].dtype == np.int64
    assert 5 < result["hit"].sum() < 40
    for i, answer in enumerate(answers):
        assert bool(result["hit"][i]) == answer["hit"]
        if answer["hit"]:
            assert result["t"][i] == answer["t"]
            assert list(result["point"][i]) == answer["point"]
            assert list(result["normal"][i]) == answer["normal"]
            assert keywords[result["object"][i]] == answer["object"]
        else:
            assert np.isnan(result["t"][i]) and result["object"][i] == -1


def test_probe_known_hit():
    hit = kardia.Scene.heart().probe([0, -5, 0], [0, 2, 0])
    assert hit["hit"][0] and hit["t"][0] == pytest.approx(2.0, abs=1e-12)
    np.testing.assert_allclose(hit["point"][0], [0, -1, 0], atol=1e-12)
    # On the equator curve the normal is the limit of the lower half's: unit, facing the ray.
    assert np.linalg.norm(hit["normal"][0]) == pytest.approx(1.0, abs=1e-12)
    assert hit["normal"][0] @ [0, 2, 0] < 0


def test_roots_equal_kardia_roots(cli):
    coeffs = [-6, 11, -6, 1]
    assert list(kardia.roots(coeffs, (-10, 10))) == [1.0, 2.0, 3.0]
    printed = cli("roots", "--in", "-10,10", *coeffs).stdout.split()
    assert [float(x) for x in printed] == list(kardia.roots(coeffs, (-10, 10)))
    assert list(kardia.roots(coeffs, (1.5, 10), first=True)) == [2.0]
    assert list(kardia.roots(coeffs, (1.5, 10), first=True, solver="yuksel")) == [2.0]
    assert kardia.roots([1, 0, 1]).size == 0
    double = kardia.roots(np.polynomial.polynomial.polyfromroots([0.5, 0.5, 2.0]), (0, 3))
    np.testing.assert_allclose(double, [0.5, 2.0], rtol=1e-12)


def test_heart_mesh_is_a_closed_solid():
    mesh = kardia.Scene.heart().mesh(tolerance=0.08)
    assert mesh.vertices.shape[1] == 3 and mesh.vertices.dtype == np.float64
    assert mesh.faces.shape[1] == 3 and mesh.faces.dtype == np.uint32
    assert mesh.faces.max() < len(mesh.vertices)
    # Every edge is shared by exactly two faces, in opposite directions (closed, oriented).
    edges = np.concatenate([mesh.faces[:, [0, 1]], mesh.faces[:, [1, 2]], mesh.faces[:, [2, 0]]])
    forward = {tuple(e) for e in edges}
    assert len(forward) == len(edges) and all((b, a) in forward for a, b in forward)
    need("trimesh")
    tm = mesh.to_trimesh()
    assert tm.is_watertight and tm.volume > 0
