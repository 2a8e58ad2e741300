"""kardia from Python: render implicit polynomial surfaces (the paper's heart and any surface
typed as an equation) into numpy arrays, probe rays, find polynomial roots and mesh solids.

The work is done by kardia's Rust library (the same code as the ``kardia`` command line);
renders release the GIL, stop on Ctrl-C (or a notebook's stop button) within a tile and
raise ``KeyboardInterrupt``.

>>> import kardia
>>> image = kardia.Scene.heart().render(width=200, samples=4)
>>> image.array.shape, image.array.dtype
((200, 200, 3), dtype('uint8'))
"""

from __future__ import annotations

import os
from typing import Any, Callable, Dict, Iterator, Optional, Sequence, Tuple, Union

import numpy as np

from . import _kardia
from ._kardia import MAX_SIDE, SOLVERS, VIEWS, Camera, Image, SceneError

__all__ = [
    "Camera",
    "Image",
    "Mesh",
    "Scene",
    "SceneError",
    "MAX_SIDE",
    "SOLVERS",
    "VIEWS",
    "frame_path",
    "roots",
]

__version__ = "0.1.0"

#: The camera of a scene made from an equation or preset when none is given: the explorer's
#: default view (eye, look-at, up, horizontal field of view in degrees).
DEFAULT_CAMERA = Camera((6.0, 1.2, 0.9), (0.0, 0.0, 0.05), (0.0, 0.0, 1.0), 32.0)

#: The colour of a surface made from an equation or preset (linear RGB), and of its inside.
DEFAULT_COLOUR = (0.7454, 0.0319, 0.0802)
DEFAULT_INSIDE = (0.8714, 0.6308, 0.117)

Progress = Union[bool, Callable[[int, int], Any], None]


def _number(x: float) -> str:
    """A finite float as scene text (Python's round-trip form)."""
    x = float(x)
    if not np.isfinite(x):
        raise ValueError(f"expected a finite number, not {x}")
    return repr(x)


def _vector(v: Sequence[float], name: str) -> str:
    """Three finite numbers as a scene vector ``(x, y, z)``."""
    values = list(v)
    if len(values) != 3:
        raise ValueError(f"{name} must have three components, not {len(values)}")
    return "(" + ", ".join(_number(x) for x in values) + ")"


def _camera_line(camera: Camera) -> str:
    """A camera as the scene's CAMERA statement."""
    eye, look, up = (_vector(v, "camera") for v in (camera.eye, camera.look_at, camera.up))
    if camera.orthographic_height is not None:
        return f"CAMERA {eye} {look} {up} ORTHOGRAPHIC {_number(camera.orthographic_height)}"
    return f"CAMERA {eye} {look} {up} {_number(camera.fov)}"


def _progress_callback(progress: Progress) -> Tuple[Optional[Callable[[int, int], Any]], Any]:
    """The callback the extension calls with (pixels done, pixels in all) and what to close
    afterwards: a tqdm bar for ``progress=True`` when tqdm is installed (nothing otherwise),
    the caller's callable as it is, or nothing."""
    if progress is None or progress is False:
        return None, None
    if callable(progress):
        return progress, None
    try:
        from tqdm.auto import tqdm
    except ImportError:
        return None, None
    bar = {"bar": None}

    def update(done: int, total: int) -> None:
        if bar["bar"] is None:
            bar["bar"] = tqdm(total=total, unit="px", unit_scale=True, desc="kardia", leave=False)
        bar["bar"].update(done - bar["bar"].n)

    return update, bar


def _close(handle: Any) -> None:
    if handle is not None and handle["bar"] is not None:
        handle["bar"].close()


class Scene:
    """A scene: its text in kardia's scene language (docs/scene-format.md), read once and
    rendered as often as wanted with any size, camera, view or frame. Immutable and safe to
    share between threads; pickles as its text (so it travels to Dask workers).

    Raises SceneError (a ValueError whose message is the command line's file:line:column
    report with a caret) for a text that is not a valid scene.
    """

    def __init__(self, text: str, name: str = "<string>", *, solver: str = "sturm") -> None:
        self._scene = _kardia.Scene(text, name, solver)

    @classmethod
    def _wrap(cls, inner: "_kardia.Scene") -> "Scene":
        scene = cls.__new__(cls)
        scene._scene = inner
        return scene

    @classmethod
    def from_file(cls, path: Union[str, "os.PathLike[str]"], *, solver: str = "sturm") -> "Scene":
        """A scene file: ``.scene``, SURFER's ``.jsurf`` or surf's ``.pic`` (translated as
        ``kardia render`` translates them; see ``warnings``)."""
        return cls._wrap(_kardia.Scene.from_file(os.fspath(path), solver))

    @classmethod
    def heart(cls, *, solver: str = "sturm") -> "Scene":
        """The built-in default heart (scenes/heart.scene), what ``kardia render`` renders
        without a scene."""
        return cls._wrap(_kardia.Scene.default_heart(solver))

    @classmethod
    def from_equation(
        cls,
        equation: str,
        *,
        bound: Optional[float] = None,
        scale: float = 1.0,
        colour: Sequence[float] = DEFAULT_COLOUR,
        inside: Optional[Sequence[float]] = DEFAULT_INSIDE,
        camera: Optional[Camera] = None,
        size: Tuple[int, int] = (800, 800),
        solver: str = "sturm",
    ) -> "Scene":
        """A scene of one surface typed as an equation in x, y, z (``"x^2 + y^2 + z^2 = 1"``;
        other letters need ``LET`` lines, so give numbers), scaled by ``scale`` about the
        origin, in ``colour`` (linear RGB, 0 to 1) with ``inside`` on its back side,
        clipped to a ball of radius ``bound`` (object units; default: derived for a bounded
        surface), seen by ``camera`` (default: ``DEFAULT_CAMERA``) at ``size`` pixels, lit as
        the explorer lights it."""
        if '"' in equation or "\n" in equation:
            raise ValueError("an equation cannot hold a double quote or a line break")
        return cls._one_surface(f'"{equation}"', bound, scale, colour, inside, camera, size, solver)

    @classmethod
    def from_preset(
        cls,
        preset: str,
        *params: float,
        bound: Optional[float] = None,
        scale: float = 1.0,
        colour: Sequence[float] = DEFAULT_COLOUR,
        inside: Optional[Sequence[float]] = DEFAULT_INSIDE,
        camera: Optional[Camera] = None,
        size: Tuple[int, int] = (800, 800),
        solver: str = "sturm",
    ) -> "Scene":
        """A scene of one preset surface (``"torus", 1, 0.3``; ``"kummer", 1.3``;
        ``"chmutov", 6``; the list is in docs/scene-format.md) with its parameters; the
        other arguments as for ``from_equation``."""
        if not preset.replace("_", "").isalnum():
            raise ValueError(f"{preset!r} is not a preset name")
        surface = " ".join([preset] + [_number(p) for p in params])
        return cls._one_surface(surface, bound, scale, colour, inside, camera, size, solver)

    @classmethod
    def _one_surface(cls, surface, bound, scale, colour, inside, camera, size, solver) -> "Scene":
        width, height = (int(s) for s in size)
        s = _number(scale)
        lines = [
            f"SIZE {width} {height}",
            _camera_line(camera if camera is not None else DEFAULT_CAMERA),
            "BACKGROUND (0.03, 0.03, 0.05)",
            "AMBIENT (0.06, 0.06, 0.07)",
            "LIGHT (7, -4, 6) (0.9, 0.88, 0.85) 0.6 SAMPLES 4",
            "LIGHT (3, 6, 1) (0.25, 0.25, 0.3)",
        ]
        implicit = (
            f"IMPLICIT {surface} (0, 0, 0) ({s}, 0, 0) (0, {s}, 0) (0, 0, {s}) "
            f"{_vector(colour, 'colour')} SPECULAR 0.4 60"
        )
        if inside is not None:
            implicit += f" INSIDE {_vector(inside, 'inside')}"
        if bound is not None:
            implicit += f" BOUND {_number(bound)}"
        lines.append(implicit)
        return cls("\n".join(lines) + "\n", "<equation>", solver=solver)

    def __reduce__(self):
        return (_from_text, (self.text, self.name, self.solver, self._scene.warnings))

    # --- what the scene says -------------------------------------------------------------

    @property
    def text(self) -> str:
        """The scene text (for a ``.jsurf`` or ``.pic`` file, its translation)."""
        return self._scene.text

    @property
    def name(self) -> str:
        """The name in error messages (a file's path)."""
        return self._scene.name

    @property
    def solver(self) -> str:
        """The root solver its surfaces use ("sturm" or "yuksel")."""
        return self._scene.solver

    @property
    def size(self) -> Tuple[int, int]:
        """The image size (width, height) in pixels from the scene's SIZE."""
        return self._scene.size

    @property
    def camera(self) -> Camera:
        """The scene's own camera."""
        return self._scene.camera

    @property
    def objects(self) -> list:
        """The objects as (keyword, line) pairs, in scene order (``probe``'s ``object``
        indexes this list)."""
        return self._scene.objects

    @property
    def declared_frames(self) -> Optional[int]:
        """The scene's FRAMES, or None."""
        return self._scene.declared_frames

    @property
    def fps(self) -> float:
        """Frames per second of an animated output (FPS, 24 by default)."""
        return self._scene.fps

    @property
    def animated(self) -> bool:
        """True when something in the scene depends on the time."""
        return self._scene.animated

    @property
    def warnings(self) -> list:
        """What the reader of a ``.jsurf`` or ``.pic`` file ignored."""
        return self._scene.warnings

    def frame_count(self, turntable: Optional[int] = None) -> int:
        """Frames the scene makes: ``turntable`` when given, else its FRAMES, else 1."""
        return self._scene.frame_count(turntable)

    # --- rendering -------------------------------------------------------------------

    def render(
        self,
        width: Optional[int] = None,
        height: Optional[int] = None,
        *,
        samples: int = 4,
        seed: int = 0,
        threads: Optional[int] = None,
        view: str = "shaded",
        camera: Optional[Camera] = None,
        alpha: bool = False,
        max_depth: int = 8,
        linear: bool = False,
        region: Optional[Tuple[int, int, int, int]] = None,
        tile: Optional[Tuple[int, int]] = None,
        frame: Optional[int] = None,
        turntable: Optional[int] = None,
        progress: Progress = None,
    ) -> Image:
        """Renders the scene as ``kardia render`` does with the same settings, into an
        ``Image`` whose ``array`` is uint8 sRGB (H, W, 3), or (H, W, 4) with straight alpha,
        or with ``linear=True`` float32 linear RGB (premultiplied RGBA with ``alpha``); row 0
        is the top (matplotlib's ``imshow`` convention).

        - ``width``/``height``: pixels (1 to MAX_SIDE); one alone keeps the scene's aspect;
          neither, the scene's SIZE.
        - ``samples`` per pixel (1 to 65536), ``seed`` (≥ 0), ``max_depth`` of mirrors and
          glass, ``threads`` (default one per core).
        - ``view``: one of ``VIEWS`` ("shaded", "normals", "depth", and the root finder's
          study views "roots", "path", "iterations", "conditioning").
        - ``camera``: a ``Camera`` instead of the scene's; ``alpha``: a transparent
          background (each pixel's alpha its coverage).
        - ``region=(x, y, w, h)`` or ``tile=(i, n)`` (row band i of n): only those pixels of
          the full image, exactly as in the full render.
        - ``frame``: frame n of the scene's FRAMES (or of the ``turntable`` of that many
          frames), read at its time with its own seed, as ``kardia render --frame n``.
        - ``progress``: True for a tqdm bar (when tqdm is installed), or a callable
          ``f(done, total)`` (pixels), called from this thread while the render runs.

        Releases the GIL while rendering. Ctrl-C (a notebook's stop) cancels it within a tile
        and raises KeyboardInterrupt. Bad arguments raise ValueError or TypeError.
        """
        callback, handle = _progress_callback(progress)
        try:
            return self._scene.render(
                width=width,
                height=height,
                samples=samples,
                seed=seed,
                threads=threads,
                view=view,
                camera=camera,
                alpha=alpha,
                max_depth=max_depth,
                linear=linear,
                region=region,
                tile=tile,
                frame=frame,
                turntable=turntable,
                progress=callback,
            )
        finally:
            _close(handle)

    def frames(
        self,
        frames: Optional[Union[range, Sequence[int]]] = None,
        *,
        turntable: Optional[int] = None,
        **render_options: Any,
    ) -> Iterator[Image]:
        """The frames of an animated scene (its FRAMES) or of a turntable of ``turntable``
        frames, one ``Image`` at a time, each as ``render(frame=n)`` makes it (and as
        ``kardia render --frame n`` writes it). ``frames``: which (default all, in order).
        Other keywords as for ``render``."""
        count = self.frame_count(turntable)
        numbers = range(count) if frames is None else frames
        for n in numbers:
            yield self.render(frame=n, turntable=turntable, **render_options)

    def probe(self, origins: Any, directions: Any) -> Dict[str, np.ndarray]:
        """Rays ``origins[i] + t·directions[i]`` ((N, 3) or (3,) array-likes of world
        coordinates; directions need not be unit length) intersected with the scene, each as
        ``kardia probe`` answers it. Returns a dict of arrays: ``hit`` (N,) bool, ``t`` (N,)
        (NaN where missed), ``point`` and ``normal`` (N, 3) (the unit normal faces out of
        the solid; NaN where missed), ``object`` (N,) int64 (index into ``objects``, -1
        where missed). Raises ValueError for other shapes, NaN or infinite numbers,
        coordinates beyond ±1e6 or a zero direction."""
        o = np.ascontiguousarray(origins, dtype=np.float64)
        d = np.ascontiguousarray(directions, dtype=np.float64)
        if o.ndim == 1:
            o = o.reshape(1, -1)
        if d.ndim == 1:
            d = d.reshape(1, -1)
        if o.ndim != 2 or d.ndim != 2 or o.shape[1] != 3 or d.shape != o.shape:
            raise ValueError(
                f"origins and directions must both have shape (N, 3), not {np.shape(origins)} "
                f"and {np.shape(directions)}"
            )
        return self._scene.probe(o, d)

    def mesh(
        self,
        kind: str = "solid",
        *,
        thickness: Optional[float] = None,
        tolerance: Optional[float] = None,
        max_cells: int = 512,
        size: Optional[float] = None,
    ) -> "Mesh":
        """The scene's HEART and IMPLICIT solids as one closed, 2-manifold, outward-wound
        triangle mesh, as ``kardia mesh`` makes it: ``kind`` "solid" (inside the surface,
        within its clip ball), "outside", or "shell" with ``thickness``; ``tolerance`` the
        grid accuracy in scene units (default 1 % of each clip radius); ``size`` scales the
        whole so its largest extent is that. Raises ValueError when there is nothing to
        mesh or an argument is out of range."""
        vertices, faces = self._scene.mesh(kind, thickness, tolerance, max_cells, size)
        return Mesh(vertices, faces)

    def __repr__(self) -> str:
        return repr(self._scene)


def _from_text(text: str, name: str, solver: str, warnings: list) -> Scene:
    """Unpickles a Scene (its text, name and solver)."""
    scene = Scene(text, name, solver=solver)
    return scene


class Mesh:
    """A triangle mesh: ``vertices`` (V, 3) float64 and ``faces`` (F, 3) uint32, each face
    wound counter-clockwise seen from outside (its right-hand normal faces out)."""

    def __init__(self, vertices: np.ndarray, faces: np.ndarray) -> None:
        self.vertices = vertices
        self.faces = faces

    def to_trimesh(self) -> Any:
        """The mesh as a ``trimesh.Trimesh`` (needs ``pip install trimesh``)."""
        try:
            import trimesh
        except ImportError as e:  # pragma: no cover - depends on the environment
            raise ImportError("Mesh.to_trimesh needs trimesh: pip install trimesh") from e
        return trimesh.Trimesh(vertices=self.vertices, faces=self.faces, process=False)

    def __repr__(self) -> str:
        return f"Mesh({len(self.vertices)} vertices, {len(self.faces)} faces)"


def roots(
    coeffs: Sequence[float],
    interval: Tuple[float, float] = (-np.inf, np.inf),
    *,
    first: bool = False,
    solver: str = "sturm",
) -> np.ndarray:
    """The distinct real roots t with lo < t ≤ hi of c0 + c1·t + … + cn·tⁿ (``coeffs`` in
    ascending powers, 1 to 17 finite numbers), ascending, as a float64 array, as ``kardia
    roots`` prints them; ``first=True``: only the smallest. Raises ValueError for bad
    input."""
    c = np.asarray(coeffs, dtype=np.float64)
    if c.ndim != 1:
        raise ValueError(f"coeffs must be one-dimensional, not of shape {c.shape}")
    lo, hi = (float(x) for x in interval)
    return _kardia.roots(c.tolist(), (lo, hi), first, solver)


def frame_path(pattern: Union[str, "os.PathLike[str]"], frame: int) -> str:
    """The file of ``frame`` for an output pattern such as ``out/heart_####.png``: the last
    run of ``#`` in the file name becomes the frame number, zero-padded to its length, as
    ``kardia render --frames`` names its files."""
    return _kardia.frame_path(os.fspath(pattern), frame)
