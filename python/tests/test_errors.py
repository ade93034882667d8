"""Every bad input is a Python exception with the CLI's message."""

import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import lambert
from conftest import MESHES

TRIANGLE = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=np.float64)


@pytest.mark.parametrize(
    "vertices, faces, message",
    [
        ([[0, 0, 0], [1, np.nan, 0], [0, 1, 0]], [[0, 1, 2]], "vertices row 1"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, np.inf]], [[0, 1, 2]], "vertices row 2"),
        ([[0, 0, 0], [1, 0, 0], [0, 1e10, 0]], [[0, 1, 2]], "vertices row 2"),
        (TRIANGLE, [[0, 1, 2], [0, 1, 3]], "faces row 1"),
        (TRIANGLE, [[0, 1, 2], [0, 1, 2], [-1, 1, 2]], "faces row 2"),
        (TRIANGLE, [[0, 1]], "(F, 3)"),
        (TRIANGLE[:, :2], [[0, 1, 2]], "(V, 3)"),
        (TRIANGLE, [[0.0, 1.0, 2.0]], "integer"),
        (TRIANGLE.astype(complex), [[0, 1, 2]], "float"),
        (TRIANGLE, [[0, 1, 2]], None),
    ],
)
def test_bad_arrays_name_the_row(vertices, faces, message):
    if message is None:
        lambert.Scene.from_arrays(vertices, faces, albedo=[0.5, 0.6, 0.7])
        return
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        lambert.Scene.from_arrays(vertices, faces)


def test_out_of_range_index_message():
    with pytest.raises(ValueError) as e:
        lambert.Scene.from_arrays(TRIANGLE, [[0, 1, 7]])
    assert "faces row 0 = [0, 1, 7]: index 7 is out of range (there are 3 vertices" in str(e.value)


def test_bad_albedo():
    with pytest.raises(ValueError, match="albedo"):
        lambert.Scene.from_arrays(TRIANGLE, [[0, 1, 2]], albedo=[np.nan, 0, 0])


@pytest.mark.parametrize(
    "origin, direction, tmin, tmax, message",
    [
        ([np.nan, 0, 0], [0, 0, 1], 0.0, np.inf, "ray 1: ox is NaN"),
        ([0, 0, 0], [0, 0, 0], 0.0, np.inf, "ray 1: the direction (dx, dy, dz) has length 0"),
        ([0, 0, 0], [0, np.inf, 1], 0.0, np.inf, "ray 1: dy is inf"),
        ([0, 0, 0], [0, 0, 1], 2.0, 1.0, "ray 1: tmin = 2 is greater than tmax = 1"),
        ([0, 0, 0], [0, 0, 1], -np.inf, 1.0, "ray 1: tmin is -inf"),
        ([0, 0, 1e39], [0, 0, 1], 0.0, np.inf, "ray 1: oz is inf"),  # beyond float32
    ],
)
@pytest.mark.parametrize("device", ["cpu", "gpu"])
def test_bad_rays_name_the_ray_and_field(origin, direction, tmin, tmax, message, device):
    scene = lambert.Scene.from_arrays(TRIANGLE, [[0, 1, 2]])
    o = np.array([[0.2, 0.2, 1.0], origin], dtype=np.float64)
    d = np.array([[0, 0, -1.0], direction], dtype=np.float64)
    lo = np.array([0.0, tmin])
    hi = np.array([np.inf, tmax])
    for query in (scene.intersect, scene.occluded):
        with pytest.raises(ValueError) as e:
            query(o, d, lo, hi, device=device)
        assert message in str(e.value)


@pytest.mark.parametrize("device", ["cpu", "gpu"])
def test_bad_rays_among_many_packed_float32_rays_name_the_first(device):
    # Packed float32 rows with scalar bounds: the CPU path reads and
    # checks them chunk by chunk as it traces; the first bad ray is named.
    scene = lambert.Scene.from_arrays(TRIANGLE, [[0, 1, 2]])
    n = 5000
    o = np.tile(np.array([[0.2, 0.2, 1.0]], dtype=np.float32), (n, 1))
    d = np.tile(np.array([[0.0, 0.0, -1.0]], dtype=np.float32), (n, 1))
    o[4321, 0] = np.nan
    d[3100] = 0.0
    for query in (scene.intersect, scene.occluded):
        with pytest.raises(ValueError) as e:
            query(o, d, device=device)
        assert "ray 3100: the direction (dx, dy, dz) has length 0" in str(e.value)
    d[3100] = [0.0, 0.0, -1.0]
    with pytest.raises(ValueError, match="ray 4321: ox is NaN"):
        scene.intersect(o, d, device=device)
    o[4321, 0] = 0.2
    assert (scene.intersect(o, d, device=device)["prim_id"] == 0).all()


def test_bad_query_arguments():
    scene = lambert.Scene.from_arrays(TRIANGLE, [[0, 1, 2]])
    o, d = np.zeros((2, 3)), np.ones((2, 3))
    cases = [
        (lambda: scene.intersect(o, d[:1]), "2 origins but 1 directions"),
        (lambda: scene.intersect(o[:, :2], d), r"origins has shape \(2, 2\)"),
        (lambda: scene.intersect(o, d, tmin=[0.0, 0.0, 0.0]), "tmin has shape"),
        (lambda: scene.intersect(o, d, tmax="far"), "tmax must be"),
        (lambda: scene.intersect(o, d, device="tpu"), 'device="tpu"'),
        (lambda: scene.intersect(o, d, intersect="fast"), 'intersect="fast"'),
        (lambda: scene.intersect(np.zeros(2)), "RAY_DTYPE"),
        (lambda: scene.intersect(np.zeros(2, dtype=lambert.RAY_DTYPE), tmax=1.0), "carry their own"),
        (lambda: scene.render(spp=0), "spp = 0"),
        (lambda: scene.render(width=0, height=10), "width"),
        (lambda: scene.camera_rays(width=100000, height=100000), "width"),
    ]
    for call, message in cases:
        with pytest.raises(ValueError, match=message):
            call()


def test_files_that_cannot_be_read_are_os_errors(tmp_path):
    with pytest.raises(FileNotFoundError, match="nothing.obj"):
        lambert.Scene.load(tmp_path / "nothing.obj")
    folder = tmp_path / "folder.obj"
    folder.mkdir()
    with pytest.raises(OSError, match="folder.obj"):
        lambert.Scene.load(folder)


def test_malformed_files_are_value_errors_with_file_and_line(tmp_path):
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
    with pytest.raises(ValueError, match=r"bad.obj:4"):
        lambert.Scene.load(bad)
    toml = tmp_path / "bad.toml"
    toml.write_text("[camera]\neye = [0, 0, 1]\n")
    with pytest.raises(ValueError, match="bad.toml"):
        lambert.Scene.load(toml)
    stl = tmp_path / "bad.stl"
    stl.write_text("solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 x 0\n")
    with pytest.raises(ValueError, match=r"bad.stl:5: facet 0, vertex 1: 'x' is not a number"):
        lambert.Scene.load(stl)
    # STL is read since issue 30; a 3DS file is not.
    with pytest.raises(ValueError, match="not a scene"):
        lambert.Scene.load(tmp_path / "model.3ds")


def test_write_image_errors_leave_the_previous_file(tmp_path):
    image = np.full((4, 5, 3), 0.5, dtype=np.float32)
    target = tmp_path / "out.png"
    lambert.write_image(target, image)
    before = target.read_bytes()
    with pytest.raises(ValueError, match="shape"):
        lambert.write_image(target, image[:, :, :2])
    with pytest.raises(ValueError, match="unknown image format"):
        lambert.write_image(tmp_path / "out.jpg", image)
    assert target.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.png"]
    with pytest.raises(OSError):
        lambert.write_image(tmp_path / "out.png" / "inside.png", image)


def run_isolated(code, **env):
    """Runs `code` in a fresh interpreter (so that its device state is its own)."""
    full_env = {**os.environ, "NODEVICE_SELECT": "1", **env}
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True,
                          env=full_env, timeout=300)


NO_ADAPTER = {"VK_ICD_FILENAMES": "/nonexistent/icd.json", "VK_DRIVER_FILES": "/nonexistent/icd.json",
              "WGPU_BACKEND": "vulkan"}


def test_gpu_without_an_adapter_raises_and_says_how_to_get_lavapipe():
    done = run_isolated(f"""
        import lambert
        scene = lambert.Scene.load({os.path.join(MESHES, 'cube.obj')!r})
        try:
            scene.intersect([[0, 0, 5]], [[0, 0, -1]], device="gpu")
        except RuntimeError as e:
            print("RuntimeError:", e)
    """, **NO_ADAPTER)
    assert "RuntimeError: GPU: no GPU adapter" in done.stdout, done.stdout + done.stderr
    assert "mesa-vulkan-drivers" in done.stdout


def test_auto_without_a_gpu_falls_back_to_the_cpu_with_a_warning():
    done = run_isolated(f"""
        import warnings, lambert
        scene = lambert.Scene.load({os.path.join(MESHES, 'cube.obj')!r})
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            hit = scene.intersect([[0, 0, 5]], [[0, 0, -1]], device="auto")
            again = scene.intersect([[0, 0, 5]], [[0, 0, -1]], device="auto")
        print("t", hit["t"][0], again["t"][0])
        print("warnings", len(caught), caught[0].category.__name__, str(caught[0].message).splitlines()[-1])
        print("device", scene.device("auto"))
    """, **NO_ADAPTER)
    assert "t 4.5 4.5" in done.stdout, done.stdout + done.stderr
    # Once per scene, as the CLI says it once per run.
    assert "warnings 1 RuntimeWarning note: using the CPU path instead" in done.stdout
    assert "device CPU" in done.stdout


@pytest.mark.parametrize("vertices", [TRIANGLE, np.zeros((0, 3))])
def test_a_mesh_without_faces_is_a_value_error(vertices):
    for faces in (np.zeros((0, 3), dtype=np.int64), np.zeros((0, 3), dtype=np.uint32), np.zeros((0, 3)), []):
        with pytest.raises(ValueError, match=rf"no triangles \({len(vertices)} points\)"):
            lambert.Scene.from_arrays(vertices, np.asarray(faces).reshape(0, 3))


def test_per_face_albedo_names_the_shapes_it_takes():
    faces = [[0, 1, 2], [0, 2, 1]]
    with pytest.raises(ValueError, match=r"albedo has shape \(2, 3\); .*shape \(3,\)"):
        lambert.Scene.from_arrays(TRIANGLE, faces, albedo=np.full((2, 3), 0.5))
    # One colour, as a number or (r, g, b), is the mesh's.
    for albedo in (0.5, [0.5], (0.2, 0.3, 0.4), np.array([0.2, 0.3, 0.4], dtype=np.float32)):
        lambert.Scene.from_arrays(TRIANGLE, faces, albedo=albedo)


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda s: s.render(-1, 5), r"width = -1: must be a positive whole number"),
        (lambda s: s.render(5, -3), r"height = -3: must be a positive whole number"),
        (lambda s: s.render(5, 5, spp=-2), r"spp = -2: must be a positive whole number"),
        (lambda s: s.render(2**40, 5), r"width = 1099511627776 is too large"),
        (lambda s: s.camera_rays(-1), r"width = -1"),
        (lambda s: s.camera_rays(height=-1), r"height = -1"),
    ],
)
def test_negative_and_huge_sizes_are_value_errors_naming_the_argument(call, message):
    scene = lambert.Scene.from_arrays(TRIANGLE, [[0, 1, 2]])
    with pytest.raises(ValueError, match=message):
        call(scene)
    with pytest.raises(TypeError, match="whole number"):
        scene.render(2.5, 5)


def test_write_image_under_a_file_says_the_parent_is_not_a_folder(tmp_path):
    image = np.full((2, 2, 3), 0.5, dtype=np.float32)
    (tmp_path / "file.py").write_text("print()\n")
    for target in (tmp_path / "file.py" / "x.png", tmp_path / "file.py" / "deeper" / "x.png"):
        with pytest.raises(NotADirectoryError) as e:
            lambert.write_image(target, image)
        assert str(e.value) == f"{target}: cannot write there: {tmp_path / 'file.py'} is not a folder"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file.py"]
    # A missing folder is made, as the CLI makes one.
    lambert.write_image(tmp_path / "new" / "x.png", image)
    assert (tmp_path / "new" / "x.png").is_file()


def test_a_gpu_probe_prints_nothing_without_xdg_runtime_dir():
    env = {k: v for k, v in os.environ.items() if k not in ("XDG_RUNTIME_DIR", "NODEVICE_SELECT")}
    code = f"""
        import os, lambert
        scene = lambert.Scene.from_arrays({TRIANGLE.tolist()!r}, [[0, 1, 2]])
        hit = scene.intersect([[0.2, 0.2, 1.0]], [[0.0, 0.0, -1.0]], device="gpu")
        print("t", hit["t"][0], scene.device("gpu"), "NODEVICE_SELECT", os.environ.get("NODEVICE_SELECT"))
    """
    done = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True,
                          env=env, timeout=300)
    assert "t 1.0 GPU:" in done.stdout, done.stdout + done.stderr
    assert "NODEVICE_SELECT 1" in done.stdout
    assert done.stderr == "", done.stderr
    # The user's own setting stands.
    done = run_isolated("""
        import os, lambert
        print("NODEVICE_SELECT", os.environ.get("NODEVICE_SELECT"))
    """, NODEVICE_SELECT="0")
    assert "NODEVICE_SELECT 0" in done.stdout, done.stdout + done.stderr


def test_lambert_trimesh_is_there_after_import_lambert_even_without_trimesh():
    for block in ("", "sys.modules['trimesh'] = None  # import trimesh raises ImportError"):
        done = run_isolated(f"""
            import sys
            {block}
            import lambert
            print(lambert.trimesh.RayMeshIntersector.__name__)
        """)
        assert done.stdout == "RayMeshIntersector\n", (block, done.stdout + done.stderr)


@pytest.mark.parametrize(
    "name, text, expected",
    [
        ("empty.obj", "", "no triangles (0 points"),
        ("points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n", "no triangles (3 points"),
        ("lines.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\nl 2 3\n", "no triangles (3 points, 2 lines skipped)"),
        ("points.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
         "property float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n"
         "0 0 0\n1 0 0\n0 1 0\n", "no triangles (3 points"),
        ("empty.stl", "solid Empty\nendsolid Empty\n", "no triangles (0 points"),
    ],
)
def test_a_model_file_without_triangles_is_a_value_error_naming_it(tmp_path, name, text, expected):
    # The CLI's rule for every format (issue 28, item 13), through Scene.load.
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(ValueError) as e:
        lambert.Scene.load(path)
    assert str(e.value).startswith(f"{path}: ") and expected in str(e.value), str(e.value)
