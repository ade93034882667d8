"""Images: :class:`Image` (what ``Scene.render`` returns, shown inline by
Jupyter), :func:`to_srgb`, :func:`write_image`, :func:`merge`, and
:class:`Camera`."""

import os

import numpy as np

from . import _lambert
from ._errors import LambertNotADirectoryError, LambertTypeError, LambertValueError


class Image(np.ndarray):
    """A render: an (H, W, 3) float32 array of linear RGB (a numpy array in
    every way: ``np.asarray(image)`` is the plain array, no copy).

    Jupyter shows it inline (``_repr_png_``: 8-bit sRGB, as
    :func:`write_image` writes a .png). ``part`` is None, or for a tile of
    a render (``render(tile=(k, n))``) what :func:`merge` needs to place
    it: ``((k, n), (first_row, end_row), full_height, settings_hash)``.
    """

    def __new__(cls, array, part=None, scene=None):
        obj = np.asarray(array, dtype=np.float32).view(cls)
        obj.part = part
        obj._scene = scene
        return obj

    def __array_finalize__(self, obj):
        # A view or a result of arithmetic keeps where it came from; a
        # slice of a tile is refused by merge and write_image by its shape.
        self.part = getattr(obj, "part", None)
        self._scene = getattr(obj, "_scene", None)

    def _repr_png_(self):
        # A slice that is no longer (H, W, 3) shows as an array.
        if self.ndim != 3 or self.shape[2] != 3 or 0 in self.shape:
            return None
        return _lambert.png_bytes(_rgb("image", self))


def _rgb(name, image):
    """An (H, W, 3) float32 C-ordered array of ``image``."""
    a = np.asarray(image)
    if a.dtype.kind not in "fiu":
        raise LambertTypeError(f"{name} must be a real-valued (H, W, 3) array, not {a.dtype}")
    if a.ndim != 3 or a.shape[2] != 3:
        raise LambertValueError(f"{name} has shape {a.shape}; it must be (H, W, 3)")
    return np.ascontiguousarray(a, dtype=np.float32)


def to_srgb(image):
    """The 8-bit sRGB encoding of a linear-RGB (H, W, 3) image: an
    (H, W, 3) uint8 array, the pixels :func:`write_image` puts in a .png
    (values clamped to [0, 1], the sRGB curve, rounded)."""
    return _lambert.to_srgb(_rgb("image", image))


def write_image(path, image, *, scene=None):
    """Writes a linear-RGB (H, W, 3) image as .png (8-bit sRGB), .exr or
    .pfm (float32), chosen by the extension, atomically: a failed write
    leaves no partial file and any previous one untouched. Never over a
    file the scene was read from (``scene``, or the scene an
    :class:`Image` was rendered from): a ``LambertValueError`` names it. A
    tile (``render(tile=...)``) written as .exr is a part file that
    ``lambert merge`` and :func:`merge` read, as ``lambert render --tile``
    writes it."""
    rgb = _rgb("image", image)
    path = os.fspath(path)
    # A file where a folder of the path should be: the native write would
    # fail creating the folder, with the OS's bare "File exists".
    folder = os.path.dirname(os.path.abspath(path))
    while not os.path.exists(folder):
        folder = os.path.dirname(folder)
    if not os.path.isdir(folder):
        raise LambertNotADirectoryError(f"{path}: cannot write there: {folder} is not a folder")
    if scene is None:
        native = getattr(image, "_scene", None)
    else:
        native = getattr(scene, "_native", None)
        if native is None:
            raise LambertTypeError(f"scene must be a lambert.Scene, not {type(scene).__name__}")
    part = getattr(image, "part", None)
    if part is not None and not path.lower().endswith(".exr"):
        part = None  # a tile as a picture: only an .exr is a part file
    _lambert.write_image(path, rgb, native, part)


def merge(parts):
    """The image that the parts of one tiled render make, as ``lambert
    merge`` joins them: ``parts`` lists tiles that ``render(tile=(k, n))``
    returned and/or paths of part files (``lambert render --tile``'s, or
    tiles written by :func:`write_image`), each of one render, every part
    once. Returns an :class:`Image`, (H, W, 3) float32. A missing,
    duplicated or foreign part is a ``LambertValueError`` naming it."""
    if isinstance(parts, (str, bytes, os.PathLike, np.ndarray)):
        raise LambertTypeError("parts must be a list of tiles or part files")
    try:
        items = list(parts)
    except TypeError:
        raise LambertTypeError(f"parts must be a list of tiles or part files, not {type(parts).__name__}") from None
    given = []
    for i, part in enumerate(items):
        if isinstance(part, (str, os.PathLike)):
            given.append(os.fspath(part))
        elif getattr(part, "part", None) is not None:
            given.append((_rgb(f"parts[{i}]", part), part.part))
        else:
            raise LambertTypeError(
                f"parts[{i}] is neither a tile (an Image from render(tile=...)) nor a part file's path"
            )
    return Image(_lambert.merge(given))


class Camera:
    """A pinhole camera: ``eye`` and ``look_at`` (world points), ``up``
    (a vector, at least 1e-6 rad from the view direction; the TOML
    format's default is (0, 1, 0)) and ``vfov``, the
    vertical field of view in degrees, in (0, 180): the TOML format's
    ``[camera]`` (docs/scene-format.md) without its size, which
    ``render(width, height)`` gives."""

    __slots__ = ("eye", "look_at", "up", "vfov")

    def __init__(self, eye, look_at, up, vfov):
        self.eye = _point("camera.eye", eye)
        self.look_at = _point("camera.look_at", look_at)
        self.up = _point("camera.up", up)
        try:
            self.vfov = float(vfov)
        except (TypeError, ValueError):
            raise LambertTypeError(f"camera.vfov must be a number, not {type(vfov).__name__}") from None

    def __repr__(self):
        return f"lambert.Camera(eye={self.eye}, look_at={self.look_at}, up={self.up}, vfov={self.vfov})"

    def _native(self):
        return (self.eye, self.look_at, self.up, self.vfov)


def _point(name, value):
    """Three real numbers, as a tuple of floats (the library checks that
    they are finite and in range)."""
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise LambertTypeError(f"{name} must be three numbers, not {type(value).__name__}") from None
    if a.shape != (3,):
        raise LambertValueError(f"{name} has shape {a.shape}; it must be three numbers (x, y, z)")
    return tuple(float(c) for c in a)
