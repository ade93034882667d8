"""docs/python.md's example runs as it stands."""

import os
import re

import numpy as np

from conftest import ROOT


def test_the_documented_example_runs(tmp_path, monkeypatch):
    with open(os.path.join(ROOT, "docs", "python.md")) as f:
        text = f.read()
    example = re.search(r"## Example.*?```python\n(.*?)```", text, re.S).group(1)
    monkeypatch.chdir(tmp_path)
    namespace = {}
    exec(compile(example, "docs/python.md", "exec"), namespace)
    depth = namespace["depth"]
    assert depth.shape == (256, 256)
    # The height field spans [-1, 1]²; the grid [-1.2, 1.2]²: the middle
    # hits at depth 2 - y, the corners miss.
    assert np.isfinite(depth[128, 128]) and abs(depth[128, 128] - 2.0) < 0.2
    assert np.isinf(depth[0, 0])
    assert namespace["in_shadow"].dtype == bool
    assert (tmp_path / "depth.png").stat().st_size > 1000
    assert (tmp_path / "render.png").stat().st_size > 1000
