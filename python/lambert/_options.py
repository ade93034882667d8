"""A render's keyword arguments checked and put as the native module
takes them (the library checks the values' ranges, as it does the CLI's
options, and names the keyword)."""

import math
import operator
import os
import sys

import numpy as np

from . import _lambert
from ._errors import LambertTypeError, LambertValueError


def _count(name, value):
    """A width, height or sample count: None, or a whole number that fits
    (the native module says what range it takes)."""
    if value is None:
        return None
    if isinstance(value, bool):
        raise LambertTypeError(f"{name} must be a whole number, not bool")
    try:
        n = operator.index(value)
    except TypeError:
        raise LambertTypeError(f"{name} must be a whole number, not {type(value).__name__}") from None
    if n < 0:
        raise LambertValueError(f"{name} = {n}: must be a positive whole number")
    if n > 0xFFFFFFFF:
        raise LambertValueError(f"{name} = {n} is too large")
    return n


def _number(name, value):
    """A float from a Python or numpy number."""
    if isinstance(value, (bool, str, bytes)):
        raise LambertTypeError(f"{name} must be a number, not {type(value).__name__}")
    try:
        return float(value)
    except (TypeError, ValueError):
        raise LambertTypeError(f"{name} must be a number, not {type(value).__name__}") from None


def _positive(name, value):
    """A finite number > 0 (a time budget, a target error), or None."""
    if value is None:
        return None
    v = _number(name, value)
    if not (math.isfinite(v) and v > 0):
        raise LambertValueError(f"{name} = {v} must be a finite number > 0")
    return v


def _colour(name, value):
    """A linear RGB colour: one number (grey) or three, finite and ≥ 0."""
    try:
        a = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise LambertTypeError(f"{name} must be a number or (r, g, b), not {type(value).__name__}") from None
    if a.shape not in ((), (1,), (3,)):
        raise LambertValueError(f"{name} has shape {a.shape}; give one number (grey) or (r, g, b)")
    rgb = [float(c) for c in np.broadcast_to(a, (3,))]
    if not all(math.isfinite(c) and 0 <= c <= np.finfo(np.float32).max for c in rgb):
        raise LambertValueError(f"{name} = {rgb} must be finite and non-negative")
    return rgb


def _environment(value, strength, rotation):
    """(text, strength, rotation) as ``--environment`` takes them: a file's
    path, or "r,g,b" (exact: repr round-trips a float)."""
    if value is None:
        if strength != 1.0 or rotation != 0.0:
            raise LambertValueError("environment_strength and environment_rotation need environment=")
        return None
    if isinstance(value, (str, os.PathLike)):
        text = os.fspath(value)
        if not text:
            raise LambertValueError("environment is an empty path")
    else:
        text = ",".join(repr(c) for c in _colour("environment", value))
    return (text, _number("environment_strength", strength), _number("environment_rotation", rotation))


def _camera(camera):
    """(view, name): a Camera's (eye, look_at, up, vfov), or a glTF
    camera's name."""
    from ._image import Camera

    if camera is None:
        return None, None
    if isinstance(camera, Camera):
        return camera._native(), None
    if isinstance(camera, str):
        return None, camera
    raise LambertTypeError(
        f"camera must be a lambert.Camera or a glTF camera's name, not {type(camera).__name__}"
    )


def render_choices(width, height, *, camera=None, spp=None, seed=None, ambient=None, shadows=None,
                   integrator=None, max_depth=None, environment=None, environment_strength=1.0,
                   environment_rotation=0.0):
    """The native module's `Choices` (a dict), from a render's keywords."""
    view, name = _camera(camera)
    if shadows is not None and not isinstance(shadows, (bool, np.bool_)):
        raise LambertTypeError(f"shadows must be True or False, not {type(shadows).__name__}")
    if integrator is not None and not isinstance(integrator, str):
        raise LambertTypeError(f'integrator must be "direct" or "path", not {type(integrator).__name__}')
    return {
        "width": _count("width", width),
        "height": _count("height", height),
        "camera": view,
        "camera_name": name,
        "spp": _count("spp", spp),
        "seed": _count("seed", seed),
        "ambient": None if ambient is None else _colour("ambient", ambient),
        "shadows": None if shadows is None else bool(shadows),
        "integrator": integrator,
        "max_depth": _count("max_depth", max_depth),
        "environment": _environment(environment, environment_strength, environment_rotation),
    }


def sampling(spp, target_error, max_spp, time_budget, tile):
    """(time_budget, target_error, max_spp) checked as ``lambert render``
    checks them."""
    budget = _positive("time_budget", time_budget)
    target = _positive("target_error", target_error)
    if budget is not None and (target is not None or spp is not None):
        raise LambertValueError("time_budget chooses the spp itself: give no spp or target_error with it")
    limit = _count("max_spp", max_spp)
    if not 2 <= limit <= _lambert.MAX_SPP:
        raise LambertValueError(f"max_spp = {limit} must be between 2 and {_lambert.MAX_SPP}")
    if tile is not None and target is not None:
        raise LambertValueError(
            "tile with target_error: adaptive sampling looks at neighbouring pixels, across part edges "
            "too, so parts would not merge into the single render; use spp"
        )
    if tile is not None and budget is not None:
        raise LambertValueError("tile with time_budget: each part would choose its own spp; use spp")
    return budget, target, limit


def tile_pair(tile):
    """``tile=(k, n)``: part k of n, k from 0."""
    if tile is None:
        return None
    try:
        k, n = tile
    except (TypeError, ValueError):
        raise LambertTypeError(f"tile must be a pair (k, n), not {tile!r}") from None
    k, n = _count("tile[0]", k), _count("tile[1]", n)
    if not 0 <= k < n:
        raise LambertValueError(f"tile = ({k}, {n}): expected (k, n) with 0 ≤ k < n")
    return k, n


def progress_callback(progress):
    """``progress``: None or False (nothing), True (tqdm's bar if tqdm is
    installed, else a text bar on stderr), or a callable
    ``progress(done, total, unit)``."""
    if progress is None or progress is False:
        return None
    if progress is True:
        try:
            from tqdm.auto import tqdm
        except ImportError:
            return _TextBar()
        return _TqdmBar(tqdm)
    if callable(progress):
        return progress
    raise LambertTypeError(f"progress must be True, False, None or a callable, not {type(progress).__name__}")


class _TqdmBar:
    """tqdm's bar, one a pass (a render has one pass, a time budget two)."""

    def __init__(self, tqdm):
        self._tqdm, self._bar = tqdm, None

    def __call__(self, done, total, unit):
        if done == 0 or self._bar is None:
            if self._bar is not None:
                self._bar.close()
            self._bar = self._tqdm(total=total, unit=unit.rstrip("s") or unit, leave=False)
        self._bar.update(done - self._bar.n)
        if done >= total:
            self._bar.close()
            self._bar = None


class _TextBar:
    """A plain bar on stderr: ``[#####.....] 12/24 tiles``."""

    def __call__(self, done, total, unit):
        width = 30
        filled = width * done // max(total, 1)
        sys.stderr.write(f"\r[{'#' * filled}{'.' * (width - filled)}] {done}/{total} {unit}")
        if done >= total:
            sys.stderr.write("\n")
        sys.stderr.flush()
