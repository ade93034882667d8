"""docs/python.md's examples run as they stand, and print what their
comments say."""

import os
import re

import numpy as np
import pytest

from conftest import ROOT


def run_example(heading, tmp_path, monkeypatch):
    """Runs the first python block after the heading starting `heading`
    in tmp_path; returns its variables."""
    with open(os.path.join(ROOT, "docs", "python.md")) as f:
        text = f.read()
    example = re.search(heading + r".*?```python\n(.*?)```", text, re.S).group(1)
    monkeypatch.chdir(tmp_path)
    namespace = {}
    exec(compile(example, "docs/python.md", "exec"), namespace)
    return namespace


def test_the_documented_example_runs(tmp_path, monkeypatch):
    namespace = run_example("## Example: a depth image", tmp_path, monkeypatch)
    depth = namespace["depth"]
    assert depth.shape == (256, 256)
    # The height field spans [-1, 1]²; the grid [-1.2, 1.2]²: the middle
    # hits at depth 2 - y, the corners miss.
    assert np.isfinite(depth[128, 128]) and abs(depth[128, 128] - 2.0) < 0.2
    assert np.isinf(depth[0, 0])
    assert namespace["in_shadow"].dtype == bool
    assert (tmp_path / "depth.png").stat().st_size > 1000
    assert (tmp_path / "render.png").stat().st_size > 1000


def test_the_proximity_example_runs_and_says_what_it_prints(tmp_path, monkeypatch):
    ns = run_example("## Example: closest points", tmp_path, monkeypatch)
    # What the comments say.
    np.testing.assert_allclose(ns["near"]["point"], [[-1, 0, 0], [1, 0, 0], [0.5, 0.2, 1]], rtol=1e-6)
    np.testing.assert_allclose(ns["near"]["distance"], [1, 2, 0.1], rtol=1e-6)
    assert ns["near"]["prim_id"][0] == 0
    np.testing.assert_allclose(ns["sdf"], [-1, 2, -0.1], rtol=1e-6)
    np.testing.assert_array_equal(ns["inside"], [True, False, True])
    assert (ns["within"][:2] == -1).all() and ns["within"][2] >= 0
    np.testing.assert_array_equal(ns["counts"], [2, 1])
    np.testing.assert_allclose(ns["crossings"]["t"], [4, 6, 0.7], rtol=1e-6)
    assert ns["cup"].winding_number([[0.0, 0.0, 0.0]])[0] == pytest.approx(5 / 6, abs=1e-2)
    assert ns["ans"]["points"].dtype == np.float32 and ns["ans"]["primitive_ids"].dtype == np.uint32
    np.testing.assert_array_equal(ns["occupancy"], [1, 0, 1])


def test_the_opening_three_lines_render_the_bundled_bunny(tmp_path, monkeypatch):
    ns = run_example("# Python:", tmp_path, monkeypatch)
    image = ns["image"]
    assert isinstance(image, ns["lambert"].Image) and image.shape == (240, 320, 3) and image.dtype == np.float32
    # Lit, not black, and what a notebook shows is a PNG.
    assert image.mean() > 0.1
    assert image._repr_png_().startswith(b"\x89PNG\r\n\x1a\n")


def test_the_render_example_runs_and_says_what_it_prints(tmp_path, monkeypatch, capsys):
    ns = run_example("## Example: rendering as the command line does", tmp_path, monkeypatch)
    assert ns["image"].shape == (120, 160, 3) and ns["srgb"].dtype == np.uint8
    assert ns["srgb"].shape == (120, 160, 3)
    assert (tmp_path / "cornell.png").stat().st_size > 1000
    assert ns["origins"].shape == (4800, 3) and ns["directions"].dtype == np.float32
    # What the comments say: the tiles merge into the whole render; the
    # path-traced sky lights the room; the error names spp.
    scene = ns["scene"]
    np.testing.assert_array_equal(ns["whole"], scene.render(80, 60, spp=4, device="cpu"))
    assert ns["sky"].mean() > 0 and not np.array_equal(ns["sky"], ns["lit"])
    assert "spp = 0 must be between 1 and 4096" in capsys.readouterr().out
    assert (tmp_path / "part0.exr").stat().st_size > 0
