"""Frames and tiles of a kardia scene on a Dask cluster (``dask.distributed``).

Every frame and every tile is a pure function of the scene text, the settings and its number,
so the workers' results are exactly what one machine makes:

- ``render_frames(client, scene, frames, output="out/heart_####.png")`` renders each frame on
  a worker and writes it there (the workers must see the output folder: a local cluster, or a
  shared file system), each file byte for byte what ``kardia render SCENE --frame N -o FILE``
  writes; without ``output`` it returns the frames' arrays.
- ``render_tiles(client, scene, tiles)`` renders row bands of one image on the workers and
  joins them: the array equals the single render's.

A ``Scene`` pickles as its text, so the workers need no access to the scene file.
"""

from __future__ import annotations

from typing import Any, List, Optional, Sequence, Union

import numpy as np

from . import Scene, frame_path

__all__ = ["render_frames", "render_tiles"]


def _as_scene(scene: Union[Scene, str]) -> Scene:
    return scene if isinstance(scene, Scene) else Scene.from_file(scene)


def _frame_task(scene: Scene, frame: int, output: Optional[str], options: dict) -> Any:
    """One frame on a worker: its array, or the path it was saved to."""
    image = scene.render(frame=frame, **options)
    if output is None:
        return image.array
    path = frame_path(output, frame)
    image.save(path)
    return path


def _tile_task(scene: Scene, index: int, count: int, options: dict) -> np.ndarray:
    """Row band ``index`` of ``count`` on a worker, as an array."""
    return scene.render(tile=(index, count), **options).array


def render_frames(
    client: Any,
    scene: Union[Scene, str],
    frames: Optional[Sequence[int]] = None,
    *,
    output: Optional[str] = None,
    turntable: Optional[int] = None,
    **render_options: Any,
) -> List[Any]:
    """Renders ``frames`` (default: every frame of the scene's FRAMES or of the
    ``turntable``) of ``scene`` (a Scene or a scene file's path) on ``client``'s workers, one
    task a frame. With ``output`` (a pattern with ``####``, e.g. ``out/heart_####.png``) each
    worker writes its frame's file and the paths are returned, in the order of ``frames``;
    without it the frames' arrays are. ``render_options`` as for ``Scene.render`` (size,
    samples, seed, threads, view, …)."""
    scene = _as_scene(scene)
    if turntable is not None:
        render_options["turntable"] = turntable
    numbers = list(range(scene.frame_count(turntable)) if frames is None else frames)
    [scattered] = client.scatter([scene], broadcast=True)
    futures = [
        client.submit(_frame_task, scattered, n, output, render_options, pure=False)
        for n in numbers
    ]
    return client.gather(futures)


def render_tiles(
    client: Any,
    scene: Union[Scene, str],
    tiles: int,
    **render_options: Any,
) -> np.ndarray:
    """Renders ``scene`` as ``tiles`` row bands on ``client``'s workers and joins them: the
    array equals ``scene.render(**render_options).array`` (no alpha: parts are opaque)."""
    scene = _as_scene(scene)
    [scattered] = client.scatter([scene], broadcast=True)
    futures = [
        client.submit(_tile_task, scattered, i, tiles, render_options, pure=False)
        for i in range(tiles)
    ]
    return np.concatenate(client.gather(futures), axis=0)
