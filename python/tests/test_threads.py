"""One Scene, queried from two Python threads at once, with the GIL released."""

import os
import threading
import time

import numpy as np
import pytest

import lambert
from conftest import MESHES, random_rays


@pytest.mark.parametrize("device", ["cpu", "gpu"])
def test_two_threads_query_one_scene_at_once(device):
    scene = lambert.Scene.load(os.path.join(MESHES, "dragon_res4.obj"))
    sets = [random_rays(scene, 20000, seed=s) for s in (1, 2)]
    alone = [scene.intersect(o, d, device=device) for o, d in sets]
    alone_any = [scene.occluded(o, d, device=device) for o, d in sets]
    results, errors = {}, []

    def work(k):
        try:
            o, d = sets[k]
            for round_ in range(4):
                results[(k, round_)] = (scene.intersect(o, d, device=device), scene.occluded(o, d, device=device))
        except Exception as e:  # reported below
            errors.append(e)

    threads = [threading.Thread(target=work, args=(k,)) for k in (0, 1)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors, errors
    for (k, _), (hits, any_hit) in results.items():
        for key in ("t", "prim_id", "u", "v", "normal"):
            np.testing.assert_array_equal(hits[key], alone[k][key])
        np.testing.assert_array_equal(any_hit, alone_any[k])


def test_tracing_releases_the_gil():
    scene = lambert.Scene.load(os.path.join(MESHES, "dragon_res4.obj"))
    o, d = random_rays(scene, 400000, seed=5)
    ticks = []
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    counter = threading.Thread(target=count)
    start = time.perf_counter()
    counter.start()
    scene.intersect(o, d, device="cpu")
    end = time.perf_counter()
    stop.set()
    counter.join()
    during = [t for t in ticks if start < t < end]
    # Python code ran while lambert traced: with the GIL held, the counter
    # would have stood still for the whole trace.
    assert end - start > 0.02
    assert len(during) >= 5, (len(during), end - start)
