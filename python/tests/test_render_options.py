"""Scene.render with the command line's choices: each compared bit for bit
with `lambert render` (PFM or EXR part files read back), on scenes made
here."""

import base64
import json
import os
import struct

import numpy as np
import pytest

import lambert
from test_render import read_pfm

# A ground quad and a box standing on it: shadows, and faces at angles.
OBJ = """v -4 0 -4
v 4 0 -4
v 4 0 4
v -4 0 4
v -1 0 -1
v 1 0 -1
v 1 0 1
v -1 0 1
v -1 2 -1
v 1 2 -1
v 1 2 1
v -1 2 1
f 1 3 2
f 1 4 3
f 5 6 10
f 5 10 9
f 6 7 11
f 6 11 10
f 7 8 12
f 7 12 11
f 8 5 9
f 8 9 12
f 9 10 11
f 9 11 12
"""

EYE_A, LOOK_A = (6.0, 5.0, 9.0), (0.0, 1.0, 0.0)
EYE_B, LOOK_B = (-5.0, 3.5, 7.0), (0.3, 0.8, 0.0)


def scene_toml(folder, name, eye, look_at, vfov=40.0, shadows=True, lights=True, extra=""):
    """A TOML scene of the box on the ground, 40 x 30, seen from eye."""
    (folder / "box.obj").write_text(OBJ)
    light = """
[[point_light]]
position = [3.0, 6.0, 4.0]
intensity = [40.0, 36.0, 30.0]

[[directional_light]]
direction = [-0.3, -1.0, -0.5]
irradiance = 0.25
""" if lights else ""
    text = f"""[camera]
eye = {list(eye)}
look_at = {list(look_at)}
up = [0.0, 1.0, 0.0]
vfov = {vfov}
width = 40
height = 30

[render]
shadows = {str(shadows).lower()}

[[mesh]]
file = "box.obj"
albedo = [0.7, 0.6, 0.5]
{light}{extra}"""
    path = folder / name
    path.write_text(text)
    return str(path)


DEVICES = ["cpu", "gpu"]


@pytest.mark.parametrize("device", DEVICES)
def test_camera_shadows_ambient_spp_and_seed_equal_the_cli(device, cli, tmp_path):
    a = scene_toml(tmp_path, "a.toml", EYE_A, LOOK_A)
    # Scene B is scene A seen from another camera without shadows: what
    # the keywords make of A.
    b = scene_toml(tmp_path, "b.toml", EYE_B, LOOK_B, vfov=55.0, shadows=False)
    cli("render", b, "-o", str(tmp_path / "cli.pfm"), "--device", device, "--spp", "4", "--seed", "7",
        "--ambient", "0.1,0.2,0.3", "--width", "36", "-q")
    scene = lambert.Scene.load(a)
    image = scene.render(36, camera=lambert.Camera(EYE_B, LOOK_B, (0, 1, 0), 55.0), spp=4, seed=7,
                         ambient=(0.1, 0.2, 0.3), shadows=False, device=device)
    assert isinstance(image, lambert.Image) and image.shape == (27, 36, 3) and image.dtype == np.float32
    np.testing.assert_array_equal(image, read_pfm(tmp_path / "cli.pfm"))
    # Each choice changes the picture: none is ignored.
    plain = scene.render(36, camera=lambert.Camera(EYE_B, LOOK_B, (0, 1, 0), 55.0), spp=4, seed=7,
                         ambient=(0.1, 0.2, 0.3), device=device)
    assert not np.array_equal(plain, image)
    other_seed = scene.render(36, camera=lambert.Camera(EYE_B, LOOK_B, (0, 1, 0), 55.0), spp=4, seed=8,
                              ambient=(0.1, 0.2, 0.3), shadows=False, device=device)
    assert not np.array_equal(other_seed, image)


@pytest.mark.parametrize("device", DEVICES)
def test_lights_added_from_python_equal_the_toml_lights(device, cli, tmp_path):
    with_lights = scene_toml(tmp_path, "lit.toml", EYE_A, LOOK_A)
    dark = scene_toml(tmp_path, "dark.toml", EYE_A, LOOK_A, lights=False)
    cli("render", with_lights, "-o", str(tmp_path / "cli.pfm"), "--device", device, "-q")
    scene = lambert.Scene.load(dark)
    assert scene.render(device=device).max() == 0  # no light, no ambient: black
    scene.add_point_light((3.0, 6.0, 4.0), (40.0, 36.0, 30.0)).add_directional_light((-0.3, -1.0, -0.5), 0.25)
    np.testing.assert_array_equal(scene.render(device=device), read_pfm(tmp_path / "cli.pfm"))


def test_a_light_added_to_a_model_replaces_its_default_light(cli, tmp_path):
    model = tmp_path / "box.obj"
    model.write_text(OBJ)
    scene = lambert.Scene.load(model)
    before = scene.render(32, device="cpu")
    scene.add_spot_light((0.0, 5.0, 0.5), (0.0, -1.0, 0.0), 30.0, inner_angle_deg=10.0, outer_angle_deg=25.0)
    # The model's framed camera written as a TOML scene with the light:
    # no default light, no ambient, as a file that brings its own lights.
    c = scene.camera
    (tmp_path / "spot.toml").write_text(f"""[camera]
eye = {list(c["eye"])}
look_at = {list(c["look_at"])}
up = {list(c["up"])}
vfov = {c["vfov"]!r}
width = 32
height = 24

[[mesh]]
file = "box.obj"

[[spot_light]]
position = [0.0, 5.0, 0.5]
direction = [0.0, -1.0, 0.0]
intensity = 30.0
inner_angle_deg = 10.0
outer_angle_deg = 25.0
""")
    cli("render", str(tmp_path / "spot.toml"), "-o", str(tmp_path / "cli.pfm"), "--device", "cpu", "-q")
    after = scene.render(32, device="cpu")
    np.testing.assert_array_equal(after, read_pfm(tmp_path / "cli.pfm"))
    assert not np.array_equal(after, before)


@pytest.mark.parametrize("device", DEVICES)
def test_environment_and_path_tracing_equal_the_cli(device, cli, tmp_path):
    a = scene_toml(tmp_path, "a.toml", EYE_A, LOOK_A, lights=False)
    # A sky map written by lambert itself: bright above, dim below.
    sky = np.zeros((8, 16, 3), dtype=np.float32)
    sky[:4] = [1.0, 0.9, 0.7]
    sky[4:] = [0.1, 0.1, 0.2]
    sky[1, 3] = [40.0, 40.0, 30.0]
    lambert.write_image(tmp_path / "sky.exr", sky)
    scene = lambert.Scene.load(a)
    for environment, cli_text in [((0.2, 0.3, 0.4), "0.2,0.3,0.4"), (tmp_path / "sky.exr", str(tmp_path / "sky.exr"))]:
        out = tmp_path / "cli.pfm"
        cli("render", a, "-o", str(out), "--device", device, "--integrator", "path", "--max-depth", "3",
            "--spp", "2", "--environment", cli_text, "--environment-strength", "1.5",
            "--environment-rotation", "30", "-q")
        image = scene.render(integrator="path", max_depth=3, spp=2, environment=environment,
                             environment_strength=1.5, environment_rotation=30, device=device)
        np.testing.assert_array_equal(image, read_pfm(out))
        assert image.mean() > 0
    # The environment is the render's, not the scene's: without it, black.
    assert scene.render(integrator="path", max_depth=3, spp=2, device=device).max() == 0


def test_adaptive_sampling_equals_the_cli_and_a_time_budget_renders(cli, tmp_path):
    a = scene_toml(tmp_path, "a.toml", EYE_A, LOOK_A)
    cli("render", a, "-o", str(tmp_path / "cli.pfm"), "--device", "cpu", "--target-error", "0.02",
        "--max-spp", "32", "-q")
    scene = lambert.Scene.load(a)
    image = scene.render(target_error=0.02, max_spp=32, device="cpu")
    np.testing.assert_array_equal(image, read_pfm(tmp_path / "cli.pfm"))
    assert not np.array_equal(image, scene.render(device="cpu"))
    # A time budget chooses its spp from a timed pass: not repeatable bit
    # for bit, but the same picture within sampling noise.
    budget = scene.render(time_budget=0.5, device="cpu")
    assert budget.shape == image.shape and np.abs(budget - image).mean() < 0.05


@pytest.mark.parametrize("device", DEVICES)
def test_tiles_merge_into_the_cli_image(device, cli, tmp_path):
    a = scene_toml(tmp_path, "a.toml", EYE_A, LOOK_A)
    cli("render", a, "-o", str(tmp_path / "whole.pfm"), "--device", device, "--spp", "2", "-q")
    whole = read_pfm(tmp_path / "whole.pfm")
    scene = lambert.Scene.load(a)
    tiles = [scene.render(spp=2, tile=(k, 4), device=device) for k in range(4)]
    assert sum(t.shape[0] for t in tiles) == 30 and tiles[1].part[:3] == ((1, 4), (7, 15), 30)
    np.testing.assert_array_equal(lambert.merge(tiles[::-1]), whole)
    # The CLI's part files, and Python's tiles written as part files that
    # `lambert merge` reads: the same parts.
    for k in range(4):
        cli("render", a, "-o", str(tmp_path / f"cli{k}.exr"), "--device", device, "--spp", "2",
            "--tile", f"{k}/4", "-q")
        lambert.write_image(tmp_path / f"py{k}.exr", tiles[k])
    cli_parts = [tmp_path / f"cli{k}.exr" for k in range(4)]
    np.testing.assert_array_equal(lambert.merge(cli_parts), whole)
    np.testing.assert_array_equal(lambert.merge(cli_parts[:2] + tiles[2:]), whole)
    cli("merge", *[str(tmp_path / f"py{k}.exr") for k in range(4)], "-o", str(tmp_path / "merged.pfm"), "-q")
    np.testing.assert_array_equal(read_pfm(tmp_path / "merged.pfm"), whole)
    # Refused as `lambert merge` refuses: a part missing, twice, or of another render.
    with pytest.raises(lambert.LambertValueError, match="parts missing: 3/4"):
        lambert.merge(tiles[:3])
    with pytest.raises(lambert.LambertValueError, match="both part 1/4"):
        lambert.merge(tiles + [tiles[1]])
    other = scene.render(spp=2, seed=3, tile=(3, 4), device=device)
    with pytest.raises(lambert.LambertValueError, match="not parts of one render"):
        lambert.merge(tiles[:3] + [other])
    with pytest.raises(lambert.LambertValueError, match="target_error"):
        scene.render(tile=(0, 2), target_error=0.1)


def read_rays(path):
    rays = np.fromfile(path, dtype=lambert.RAY_DTYPE)
    origins = np.stack([rays["ox"], rays["oy"], rays["oz"]], axis=-1)
    return origins, np.stack([rays["dx"], rays["dy"], rays["dz"]], axis=-1)


def test_camera_rays_equal_the_cli(cli, tmp_path):
    a = scene_toml(tmp_path, "a.toml", EYE_A, LOOK_A)
    b = scene_toml(tmp_path, "b.toml", EYE_B, LOOK_B, vfov=55.0)
    scene = lambert.Scene.load(a)
    for path, camera in [(a, None), (b, lambert.Camera(EYE_B, LOOK_B, (0, 1, 0), 55.0))]:
        cli("camera-rays", path, "-o", str(tmp_path / "rays.bin"), "--width", "20", "-q")
        origins, directions = scene.camera_rays(20, camera=camera)
        assert origins.shape == (20 * 15, 3) and origins.dtype == np.float32
        cli_origins, cli_directions = read_rays(tmp_path / "rays.bin")
        np.testing.assert_array_equal(origins, cli_origins)
        np.testing.assert_array_equal(directions, cli_directions)


def write_gltf(path):
    """A glTF triangle with two named cameras: "front" (first) and "wide"
    (aspect ratio 2, from the side)."""
    positions = struct.pack("<9f", -1, -1, 0, 1, -1, 0, 0, 1, 0)
    gltf = {
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": len(positions),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(positions).decode()}],
        "bufferViews": [{"buffer": 0, "byteLength": len(positions)}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [-1, -1, 0], "max": [1, 1, 0]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "cameras": [
            {"name": "front", "type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1, "aspectRatio": 1.5}},
            {"name": "wide", "type": "perspective", "perspective": {"yfov": 0.6, "znear": 0.1, "aspectRatio": 2.0}},
        ],
        "nodes": [{"mesh": 0}, {"camera": 0, "translation": [0, 0, 4]},
                  {"camera": 1, "translation": [0.5, 0.3, 5]}],
        "scenes": [{"nodes": [0, 1, 2]}],
        "scene": 0,
    }
    path.write_text(json.dumps(gltf))


@pytest.mark.parametrize("device", DEVICES)
def test_a_gltf_camera_by_name_equals_the_cli(device, cli, tmp_path):
    model = tmp_path / "triangle.gltf"
    write_gltf(model)
    cli("render", str(model), "-o", str(tmp_path / "cli.pfm"), "--device", device, "--camera", "wide",
        "--width", "32", "-q")
    expected = read_pfm(tmp_path / "cli.pfm")
    assert expected.shape == (16, 32, 3)  # its aspect ratio, 2
    scene = lambert.Scene.load(model)
    np.testing.assert_array_equal(scene.render(32, camera="wide", device=device), expected)
    np.testing.assert_array_equal(lambert.Scene.load(model, camera="wide").render(32, device=device), expected)
    assert scene.render(32, device=device).shape == (21, 32, 3)  # "front", 1.5
    with pytest.raises(lambert.LambertValueError, match="no perspective camera named 'side'"):
        scene.render(32, camera="side")


def test_progress_is_told_and_its_exception_raised(tmp_path):
    scene = lambert.Scene.load(scene_toml(tmp_path, "a.toml", EYE_A, LOOK_A))
    told = []
    image = scene.render(device="cpu", progress=lambda done, total, unit: told.append((done, total, unit)))
    assert told[0] == (0, 30, "rows") and told[-1] == (30, 30, "rows")
    assert [d for d, _, _ in told] == sorted(d for d, _, _ in told)
    np.testing.assert_array_equal(image, scene.render(device="cpu", progress=True))

    def fails(done, total, unit):
        raise KeyError("stop")

    with pytest.raises(KeyError, match="stop"):
        scene.render(device="cpu", progress=fails)
    with pytest.raises(lambert.LambertTypeError, match="progress"):
        scene.render(device="cpu", progress="yes")


def test_to_srgb_png_and_the_notebook_show_the_written_png(tmp_path):
    linear = np.array([[[0.0, 1.0, 0.5], [0.001, 2.0, -1.0]]], dtype=np.float32)
    # The sRGB curve's own values: 0.5 → 0.7354 → 188; 0.001 (linear
    # segment, 12.92·x) → 3; clamped at 0 and 1.
    np.testing.assert_array_equal(lambert.to_srgb(linear), [[[0, 255, 188], [3, 255, 0]]])
    assert lambert.to_srgb(linear).dtype == np.uint8
    image = lambert.Image(linear)
    lambert.write_image(tmp_path / "a.png", image)
    assert image._repr_png_() == (tmp_path / "a.png").read_bytes()
    assert type(np.asarray(image)) is np.ndarray and np.asarray(image).dtype == np.float32
    # A row of it is no picture: the notebook shows the array instead.
    assert image[0]._repr_png_() is None


def test_write_image_never_replaces_the_scene_s_input(tmp_path):
    sky = np.ones((4, 8, 3), dtype=np.float32)
    lambert.write_image(tmp_path / "sky.exr", sky)
    path = scene_toml(tmp_path, "a.toml", EYE_A, LOOK_A, extra='\n[environment]\nimage = "sky.exr"\n')
    scene = lambert.Scene.load(path)
    image = scene.render(device="cpu")
    before = (tmp_path / "sky.exr").read_bytes()
    with pytest.raises(lambert.LambertValueError, match="sky.exr"):
        lambert.write_image(tmp_path / "sky.exr", image)
    with pytest.raises(lambert.LambertValueError, match="sky.exr"):
        lambert.write_image(tmp_path / "sky.exr", np.asarray(image), scene=scene)
    assert (tmp_path / "sky.exr").read_bytes() == before
    lambert.write_image(tmp_path / "out.exr", image)
    assert os.path.getsize(tmp_path / "out.exr") > 0


def test_progress_true_uses_tqdm_where_installed_else_a_text_bar(tmp_path, monkeypatch, capsys):
    import sys
    import types

    scene = lambert.Scene.load(scene_toml(tmp_path, "a.toml", EYE_A, LOOK_A))
    bars = []

    class FakeTqdm:
        def __init__(self, total, unit, leave):
            self.total, self.unit, self.n, self.closed = total, unit, 0, False
            bars.append(self)

        def update(self, k):
            self.n += k

        def close(self):
            self.closed = True

    module = types.ModuleType("tqdm.auto")
    module.tqdm = FakeTqdm
    monkeypatch.setitem(sys.modules, "tqdm", types.ModuleType("tqdm"))
    monkeypatch.setitem(sys.modules, "tqdm.auto", module)
    scene.render(device="cpu", progress=True)
    assert [(b.total, b.unit, b.n, b.closed) for b in bars] == [(30, "row", 30, True)]
    # Without tqdm: the text bar on stderr.
    monkeypatch.setitem(sys.modules, "tqdm.auto", None)
    capsys.readouterr()
    scene.render(device="cpu", progress=True)
    assert "30/30 rows" in capsys.readouterr().err
