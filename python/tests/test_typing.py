"""The package is typed (issue 49, item 2): its stubs and py.typed are
installed with it, and mypy, reading them, passes every example in
docs/python.md and catches a misuse."""

import os
import re
import subprocess
import sys

import lambert
from conftest import ROOT, reference_module


def mypy(tmp_path, sources):
    """mypy over `sources` (name: text), in a fresh process, as a user's
    project would run it against the installed package."""
    reference_module("mypy", "the stubs' check")
    for name, text in sources.items():
        (tmp_path / name).write_text(text)
    return subprocess.run(
        [sys.executable, "-m", "mypy", "--no-incremental", "--cache-dir", os.devnull, "--no-error-summary",
         *sources],
        capture_output=True, text=True, cwd=tmp_path, timeout=600,
    )


def test_the_stubs_and_py_typed_are_installed():
    folder = os.path.dirname(lambert.__file__)
    assert os.path.isfile(os.path.join(folder, "py.typed"))
    assert os.path.isfile(os.path.join(folder, "__init__.pyi"))


def test_mypy_passes_the_docs_examples(tmp_path):
    with open(os.path.join(ROOT, "docs", "python.md")) as f:
        blocks = re.findall(r"```python\n(.*?)```", f.read(), re.S)
    assert len(blocks) >= 4
    done = mypy(tmp_path, {f"example_{i}.py": block for i, block in enumerate(blocks)})
    assert done.returncode == 0, done.stdout + done.stderr


def test_mypy_catches_a_misuse(tmp_path):
    done = mypy(tmp_path, {"misuse.py": """import lambert
scene = lambert.Scene.load(lambert.example_path("bunny"))
scene.render(64, 48, spp="many")
image: str = scene.render(64, 48)
scene.add_point_light((0, 1, 0))
"""})
    out = done.stdout
    assert done.returncode == 1, out + done.stderr
    assert 'Argument "spp" to "render" of "Scene" has incompatible type "str"' in out, out
    assert 'incompatible types in assignment (expression has type "Image"' in out.lower() or \
        'Incompatible types in assignment (expression has type "Image"' in out, out
    assert 'Missing positional argument "intensity"' in out, out


def public_callables():
    """Every public function and class of the package, and every public
    method of Scene, with its name."""
    for name in lambert.__all__:
        value = getattr(lambert, name)
        if callable(value) and not isinstance(value, type(lambert)) and not name.startswith("Lambert"):
            yield name, value
    for name in dir(lambert.Scene):
        if not name.startswith("_"):
            yield f"Scene.{name}", getattr(lambert.Scene, name)


def test_every_public_function_has_a_docstring_with_its_shapes():
    for name, value in public_callables():
        doc = value.__doc__ or ""
        assert len(doc) > 40, f"{name} has no docstring"
    # The array-valued ones say their shape and dtype.
    for name in ("render", "camera_rays", "intersect", "occluded", "closest_points", "distance",
                 "signed_distance", "winding_number", "contains", "count_intersections"):
        doc = getattr(lambert.Scene, name).__doc__
        assert "(N" in doc or "(H, W, 3)" in doc or "(width·height, 3)" in doc, name
        assert "float32" in doc or "bool" in doc or "int32" in doc, name
    for name in ("to_srgb", "write_image", "merge"):
        assert "(H, W, 3)" in getattr(lambert, name).__doc__, name


def test_help_on_scene_reads_like_the_docs():
    import pydoc

    text = pydoc.render_doc(lambert.Scene, renderer=pydoc.plaintext)
    for words in ("lambert.Scene.load(lambert.example_path(\"bunny\"))", "(H, W, 3) float32 linear RGB",
                  "render(self, width=None, height=None, *, camera=None", "add_point_light(self, position, intensity)",
                  "LambertError"):
        assert words in text, words
