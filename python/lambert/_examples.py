"""The example scenes that come with the package (lambert/examples)."""

import os

from ._errors import LambertTypeError, LambertValueError

_FOLDER = os.path.join(os.path.dirname(os.path.abspath(__file__)), "examples")
EXAMPLES = ("bunny", "cornell")


def example_path(name):
    """The path of an example scene that comes with the package, for
    :meth:`Scene.load`: ``"bunny"`` (the Stanford bunny, 3,674 triangles,
    on a floor, with a point and a directional light) or ``"cornell"``
    (a Cornell-box-like room lit by two point lights)."""
    if not isinstance(name, str):
        raise LambertTypeError(f"name must be a str, not {type(name).__name__}")
    if name not in EXAMPLES:
        raise LambertValueError(f"name={name!r}: the examples are {', '.join(map(repr, EXAMPLES))}")
    return os.path.join(_FOLDER, f"{name}.toml")
