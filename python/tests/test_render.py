"""Renders from Python: the CLI's images, on both devices."""

import os
import warnings

import numpy as np
import pytest

import lambert
from conftest import MESHES, SCENES


def read_pfm(path):
    with open(path, "rb") as f:
        assert f.readline().strip() == b"PF"
        width, height = (int(x) for x in f.readline().split())
        scale = float(f.readline())
        data = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4")
    return data.reshape(height, width, 3)[::-1]


@pytest.mark.parametrize("device", ["cpu", "gpu"])
def test_render_equals_the_cli(device, cli, tmp_path):
    path = os.path.join(SCENES, "cornell.toml")
    cli("render", path, "-o", str(tmp_path / "cli.pfm"), "--device", device, "--width", "48", "--height", "40",
        "--spp", "4", "-q")
    image = lambert.Scene.load(path).render(48, 40, spp=4, device=device)
    assert image.shape == (40, 48, 3) and image.dtype == np.float32
    np.testing.assert_array_equal(image, read_pfm(tmp_path / "cli.pfm"))


@pytest.mark.parametrize("device", ["cpu", "gpu"])
def test_path_tracing_equals_the_cli(device, cli, tmp_path):
    path = os.path.join(SCENES, "cornell_area.toml")
    cli("render", path, "-o", str(tmp_path / "cli.pfm"), "--device", device, "--width", "32", "--height", "24",
        "--spp", "4", "--integrator", "path", "--max-depth", "5", "-q")
    scene = lambert.Scene.load(path)
    image = scene.render(32, 24, spp=4, device=device, integrator="path", max_depth=5)
    np.testing.assert_array_equal(image, read_pfm(tmp_path / "cli.pfm"))
    # The same scene, switched back to direct light (its emissive light is
    # then seen, lighting nothing): another picture, darker.
    direct = scene.render(32, 24, spp=4, device=device, integrator="direct")
    assert direct.mean() < image.mean()
    with pytest.raises(ValueError, match="integrator"):
        scene.render(8, 8, integrator="bidirectional")
    with pytest.raises(ValueError, match="max_depth"):
        scene.render(8, 8, integrator="path", max_depth=0)


@pytest.mark.parametrize("device", ["cpu", "gpu"])
def test_a_vertex_coloured_model_renders_as_the_cli_does(device, cli, tmp_path):
    # A quad whose corners are red, green, blue and white (OBJ `v x y z r g b`).
    path = tmp_path / "coloured.obj"
    path.write_text("v -1 -1 0 1 0 0\nv 1 -1 0 0 1 0\nv 1 1 0 0 0 1\nv -1 1 0 1 1 1\nf 1 2 3 4\n")
    cli("render", str(path), "-o", str(tmp_path / "cli.pfm"), "--device", device, "--width", "32", "--height", "24",
        "-q")
    scene = lambert.Scene.load(str(path))
    image = scene.render(32, 24, device=device)
    np.testing.assert_array_equal(image, read_pfm(tmp_path / "cli.pfm"))
    # Its colours, not grey: some pixel is much redder than it is green.
    assert (image[..., 0] - image[..., 1]).max() > 0.2


@pytest.mark.parametrize("device", ["cpu", "gpu"])
def test_a_textured_model_renders_as_the_cli_does(device, cli, tmp_path):
    # The bundled textured glTF: a UV-grid texture and an alpha-masked leaf.
    path = os.path.join(MESHES, "textured.glb")
    cli("render", path, "-o", str(tmp_path / "cli.pfm"), "--device", device, "--width", "64", "--height", "48", "-q")
    image = lambert.Scene.load(path).render(64, 48, device=device)
    np.testing.assert_array_equal(image, read_pfm(tmp_path / "cli.pfm"))
    # Textured, not flat: many distinct colours.
    assert len(np.unique(image.reshape(-1, 3), axis=0)) > 50


def test_gpu_and_cpu_renders_agree():
    scene = lambert.Scene.load(os.path.join(MESHES, "bunny_lowres.obj"))
    cpu = scene.render(64, 48, device="cpu")
    gpu = scene.render(64, 48, device="gpu")
    assert cpu.max() > 0.1
    np.testing.assert_allclose(cpu, gpu, atol=2e-5)
    # Its own size by default (a model alone: 1024x768), and one side alone
    # keeps the aspect ratio.
    assert scene.render(width=32, device="cpu").shape == (24, 32, 3)


def test_write_image_formats_round_trip(tmp_path, cli):
    scene = lambert.Scene.load(os.path.join(SCENES, "spheres.toml"))
    image = scene.render(40, 30, device="cpu")
    lambert.write_image(tmp_path / "a.pfm", image)
    np.testing.assert_array_equal(read_pfm(tmp_path / "a.pfm"), image)
    lambert.write_image(tmp_path / "a.png", image)
    lambert.write_image(tmp_path / "a.exr", image.astype(np.float64))
    cli("render", os.path.join(SCENES, "spheres.toml"), "-o", str(tmp_path / "cli.png"), "--device", "cpu",
        "--width", "40", "--height", "30", "-q")
    assert (tmp_path / "a.png").read_bytes() == (tmp_path / "cli.png").read_bytes()
    assert (tmp_path / "a.exr").read_bytes()[:4] == b"\x76\x2f\x31\x01"  # OpenEXR magic
    lambert.write_image(tmp_path / "new" / "folder" / "b.png", image)
    assert (tmp_path / "new" / "folder" / "b.png").exists()


def test_a_scene_file_asking_for_ray_queries_renders_the_compute_paths_image(tmp_path):
    # render.accel = "hardware" (docs/hardware-rays.md): ray queries where the
    # GPU has them, else the compute BVH with a RuntimeWarning saying so; the
    # bunny's image either way (it has no ties).
    plain = os.path.join(SCENES, "bunny.toml")
    with open(plain) as f:
        text = f.read().replace('"meshes/', '"' + MESHES + "/")
    path = tmp_path / "hardware.toml"
    path.write_text(text.replace("[render]", '[render]\naccel = "hardware"', 1))
    bvh = lambert.Scene.load(plain).render(64, 48, device="gpu")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        hardware = lambert.Scene.load(str(path)).render(64, 48, device="gpu")
    np.testing.assert_array_equal(hardware, bvh)
    notes = [str(w.message) for w in caught if "--accel hardware" in str(w.message)]
    assert all("has no ray queries" in note and "compute BVH" in note for note in notes), notes
