# Type stubs of the public API (docs/python.md); checked by mypy against
# the docs' examples (python/tests/test_typing.py).
import os
from typing import Any, Callable, Dict, Iterable, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

from . import open3d as open3d
from . import trimesh as trimesh
from ._errors import LambertError as LambertError
from ._errors import LambertFileNotFoundError as LambertFileNotFoundError
from ._errors import LambertNotADirectoryError as LambertNotADirectoryError
from ._errors import LambertOSError as LambertOSError
from ._errors import LambertPermissionError as LambertPermissionError
from ._errors import LambertRuntimeError as LambertRuntimeError
from ._errors import LambertTypeError as LambertTypeError
from ._errors import LambertValueError as LambertValueError

_Path = Union[str, os.PathLike[str]]
_Array = npt.ArrayLike
_Vector = Union[Sequence[float], npt.NDArray[Any]]
_Colour = Union[float, Sequence[float], npt.NDArray[Any]]
_Device = str
_Float32 = npt.NDArray[np.float32]
_Progress = Union[bool, None, Callable[[int, int, str], Any]]
_PartInfo = Tuple[Tuple[int, int], Tuple[int, int], int, str]

RAY_DTYPE: np.dtype[np.void]

class Camera:
    """A pinhole camera: eye, look_at, up and vfov (degrees)."""

    eye: Tuple[float, float, float]
    look_at: Tuple[float, float, float]
    up: Tuple[float, float, float]
    vfov: float
    def __init__(self, eye: _Vector, look_at: _Vector, up: _Vector, vfov: float) -> None: ...

class Image(np.ndarray[Tuple[int, int, int], np.dtype[np.float32]]):
    """A render: (H, W, 3) float32 linear RGB, shown inline by Jupyter."""

    part: Optional[_PartInfo]
    def __new__(cls, array: _Array, part: Optional[_PartInfo] = ..., scene: Any = ...) -> "Image": ...
    def _repr_png_(self) -> bytes: ...

class Scene:
    """Triangles (and spheres, materials, lights and a camera), resident
    for queries and renders."""

    @classmethod
    def from_arrays(cls, vertices: _Array, faces: _Array, albedo: Optional[_Colour] = ...) -> "Scene": ...
    @classmethod
    def load(cls, path: _Path, camera: Optional[str] = ...) -> "Scene": ...
    def intersect(
        self,
        origins: _Array,
        directions: Optional[_Array] = ...,
        tmin: Union[float, _Array] = ...,
        tmax: Union[float, _Array] = ...,
        *,
        device: _Device = ...,
        intersect: str = ...,
    ) -> Dict[str, npt.NDArray[Any]]: ...
    def occluded(
        self,
        origins: _Array,
        directions: Optional[_Array] = ...,
        tmin: Union[float, _Array] = ...,
        tmax: Union[float, _Array] = ...,
        *,
        device: _Device = ...,
        intersect: str = ...,
    ) -> npt.NDArray[np.bool_]: ...
    def closest_points(
        self, points: _Array, max_distance: float = ..., *, device: _Device = ...
    ) -> Dict[str, npt.NDArray[Any]]: ...
    def distance(self, points: _Array, *, device: _Device = ...) -> _Float32: ...
    def signed_distance(self, points: _Array, method: str = ..., *, device: _Device = ...) -> _Float32: ...
    def winding_number(self, points: _Array, *, device: _Device = ...) -> _Float32: ...
    def contains(self, points: _Array, *, device: _Device = ...) -> npt.NDArray[np.bool_]: ...
    def count_intersections(
        self,
        origins: _Array,
        directions: Optional[_Array] = ...,
        tmin: Union[float, _Array] = ...,
        tmax: Union[float, _Array] = ...,
        *,
        device: _Device = ...,
    ) -> npt.NDArray[np.int32]: ...
    def list_intersections(
        self,
        origins: _Array,
        directions: Optional[_Array] = ...,
        tmin: Union[float, _Array] = ...,
        tmax: Union[float, _Array] = ...,
        *,
        device: _Device = ...,
    ) -> Dict[str, npt.NDArray[Any]]: ...
    def camera_rays(
        self, width: Optional[int] = ..., height: Optional[int] = ..., *, camera: Union[Camera, str, None] = ...
    ) -> Tuple[_Float32, _Float32]: ...
    def render(
        self,
        width: Optional[int] = ...,
        height: Optional[int] = ...,
        *,
        camera: Union[Camera, str, None] = ...,
        spp: Optional[int] = ...,
        target_error: Optional[float] = ...,
        max_spp: int = ...,
        time_budget: Optional[float] = ...,
        seed: Optional[int] = ...,
        ambient: Optional[_Colour] = ...,
        shadows: Optional[bool] = ...,
        integrator: Optional[str] = ...,
        max_depth: Optional[int] = ...,
        environment: Union[_Path, _Colour, None] = ...,
        environment_strength: float = ...,
        environment_rotation: float = ...,
        device: _Device = ...,
        progress: _Progress = ...,
        tile: Optional[Tuple[int, int]] = ...,
    ) -> Image: ...
    def add_point_light(self, position: _Vector, intensity: _Colour) -> "Scene": ...
    def add_directional_light(self, direction: _Vector, irradiance: _Colour) -> "Scene": ...
    def add_spot_light(
        self,
        position: _Vector,
        direction: _Vector,
        intensity: _Colour,
        inner_angle_deg: float = ...,
        outer_angle_deg: float = ...,
    ) -> "Scene": ...
    def device(self, device: _Device = ...) -> str: ...
    @property
    def triangle_count(self) -> int: ...
    @property
    def sphere_count(self) -> int: ...
    @property
    def bounds(self) -> Optional[Tuple[Tuple[float, float, float], Tuple[float, float, float]]]: ...
    @property
    def camera(self) -> Dict[str, Any]: ...

def write_image(path: _Path, image: _Array, *, scene: Optional[Scene] = ...) -> None: ...
def to_srgb(image: _Array) -> npt.NDArray[np.uint8]: ...
def merge(parts: Iterable[Union[Image, _Path]]) -> Image: ...
def example_path(name: str) -> str: ...
