"""One Scene, queried from two Python threads at once, with the GIL released."""

import os
import sys
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
    # Whether another thread runs during a trace, whatever the machine's
    # speed. With a switch interval of an hour, a thread holding the GIL
    # keeps it until it blocks or releases it: the counter below, which
    # sleeps between ticks and so always waits for the GIL, can only tick
    # while this thread is inside a call that released it. Each trace is
    # repeated until the counter has ticked during one (on a fast machine
    # the first trace may end before the counter's sleep does).
    scene = lambert.Scene.load(os.path.join(MESHES, "dragon_res4.obj"))
    o, d = (a.astype(np.float32) for a in random_rays(scene, 100000, seed=5))
    ticks = [0]
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks[0] += 1
            time.sleep(0.0001)

    # Set before the counter starts, so that no wait for the GIL runs on
    # the default interval (5 ms), which would force a switch.
    interval = sys.getswitchinterval()
    sys.setswitchinterval(3600.0)
    counter = threading.Thread(target=count)
    try:
        counter.start()
        for attempt in range(200):
            before = ticks[0]
            scene.intersect(o, d, device="cpu")
            if ticks[0] > before:
                break
        ticked = ticks[0] > before
    finally:
        stop.set()
        if counter.is_alive():
            counter.join()
        sys.setswitchinterval(interval)
    assert ticked, f"no other thread ran during {attempt + 1} traces: the GIL was held"
