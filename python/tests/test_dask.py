"""The Dask recipe on a LocalCluster of two worker processes: frames byte for byte the CLI's
files, tiles joined equal to the single render."""

import numpy as np
import pytest

import kardia
from conftest import need

distributed = need("distributed")
import kardia.dask  # noqa: E402


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(
        n_workers=2,
        processes=True,
        threads_per_worker=1,
        host="127.0.0.1",
        dashboard_address=None,
    )
    with distributed.Client(cluster) as c:
        yield c
    cluster.close()


def test_frames_on_dask_are_the_cli_files(client, cli, animated_scene_file, tmp_path):
    pattern = str(tmp_path / "dask" / "frame_####.png")
    (tmp_path / "dask").mkdir()
    paths = kardia.dask.render_frames(client, str(animated_scene_file), output=pattern, threads=1)
    assert paths == [kardia.frame_path(pattern, n) for n in range(4)]
    workers = set(client.run(lambda: 1))
    assert len(workers) == 2
    for n, path in enumerate(paths):
        out = tmp_path / f"cli_{n}.png"
        cli("render", animated_scene_file, "--frame", n, "-o", out, "--quiet")
        with open(path, "rb") as mine:
            assert mine.read() == out.read_bytes(), n
    arrays = kardia.dask.render_frames(client, kardia.Scene.from_file(animated_scene_file), [1, 3])
    scene = kardia.Scene.from_file(animated_scene_file)
    np.testing.assert_array_equal(arrays[0], scene.render(frame=1).array)
    np.testing.assert_array_equal(arrays[1], scene.render(frame=3).array)


def test_tiles_on_dask_join_into_the_single_render(client, small_scene_file):
    scene = kardia.Scene.from_file(small_scene_file)
    joined = kardia.dask.render_tiles(client, scene, 4, width=64, samples=2)
    single = scene.render(width=64, samples=2).array
    assert joined.shape == single.shape
    np.testing.assert_array_equal(joined, single)
