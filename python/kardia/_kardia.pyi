"""Type stubs of kardia's extension module (the Rust library's binding)."""

from os import PathLike
from typing import Any, Callable, Dict, List, Optional, Tuple, Union

import numpy as np
import numpy.typing as npt

VIEWS: List[str]
SOLVERS: List[str]
MAX_SIDE: int

Vec3 = Tuple[float, float, float]

class SceneError(ValueError):
    """A scene that could not be read or understood: ``str(e)`` is ``kardia render``'s
    report (file:line:column: message, the line, a caret)."""

    file: str
    line: Optional[int]
    column: Optional[int]
    message: str

class Camera:
    """A pinhole camera (horizontal field of view in degrees) or an orthographic one."""

    def __init__(
        self,
        eye: Vec3,
        look_at: Vec3,
        up: Vec3 = (0.0, 0.0, 1.0),
        fov: float = 40.0,
        orthographic_height: Optional[float] = None,
    ) -> None: ...
    @property
    def eye(self) -> Vec3: ...
    @property
    def look_at(self) -> Vec3: ...
    @property
    def up(self) -> Vec3: ...
    @property
    def fov(self) -> float: ...
    @property
    def orthographic_height(self) -> Optional[float]: ...
    def orbit(self, frame: int, count: int) -> "Camera": ...

class Image:
    """A rendered image; ``array`` is uint8 sRGB or float32 linear, (H, W, 3|4), row 0 at
    the top."""

    @property
    def array(self) -> npt.NDArray[Any]: ...
    def to_array(self, linear: bool = False) -> npt.NDArray[Any]: ...
    def __array__(self, dtype: Any = None, copy: Optional[bool] = None) -> npt.NDArray[Any]: ...
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def alpha(self) -> bool: ...
    @property
    def frame(self) -> Optional[int]: ...
    @property
    def region(self) -> Tuple[int, int, int, int]: ...
    @property
    def key(self) -> str: ...
    @property
    def rays(self) -> int: ...
    @property
    def seconds(self) -> float: ...
    @property
    def threads(self) -> int: ...
    def _repr_png_(self) -> bytes: ...
    def save(self, path: Union[str, PathLike[str]], half: bool = False) -> None: ...

class Scene:
    """A loaded scene (the extension's; use ``kardia.Scene``)."""

    def __init__(self, text: str, name: str = "<string>", solver: str = "sturm") -> None: ...
    @staticmethod
    def from_file(path: Union[str, PathLike[str]], solver: str = "sturm") -> "Scene": ...
    @staticmethod
    def default_heart(solver: str = "sturm") -> "Scene": ...
    @property
    def text(self) -> str: ...
    @property
    def name(self) -> str: ...
    @property
    def solver(self) -> str: ...
    @property
    def size(self) -> Tuple[int, int]: ...
    @property
    def camera(self) -> Camera: ...
    @property
    def objects(self) -> List[Tuple[str, int]]: ...
    @property
    def declared_frames(self) -> Optional[int]: ...
    @property
    def fps(self) -> float: ...
    @property
    def animated(self) -> bool: ...
    @property
    def warnings(self) -> List[str]: ...
    def frame_count(self, turntable: Optional[int] = None) -> int: ...
    def render(
        self,
        width: Optional[int] = None,
        height: Optional[int] = None,
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
        progress: Optional[Callable[[int, int], Any]] = None,
    ) -> Image: ...
    def probe(
        self, origins: npt.NDArray[np.float64], directions: npt.NDArray[np.float64]
    ) -> Dict[str, npt.NDArray[Any]]: ...
    def mesh(
        self,
        kind: str = "solid",
        thickness: Optional[float] = None,
        tolerance: Optional[float] = None,
        max_cells: int = 512,
        size: Optional[float] = None,
    ) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.uint32]]: ...

def roots(
    coeffs: List[float],
    interval: Tuple[float, float] = ...,
    first: bool = False,
    solver: str = "sturm",
) -> npt.NDArray[np.float64]: ...
def frame_path(pattern: Union[str, PathLike[str]], frame: int) -> str: ...
