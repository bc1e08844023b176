"""kdrt.load_scene and kdrt.render: scene and model files into numpy arrays,
cancelled by Ctrl-C."""

import os
import pathlib
import signal
import threading
import time

import numpy as np
import pytest

import kdrt

ROOT = pathlib.Path(__file__).resolve().parents[2]


def test_render_a_scene_file(device):
    scene = kdrt.load_scene(str(ROOT / "scenes" / "lens.json"))
    assert scene.object_count > 0
    frame = kdrt.render(scene, device=device, width=64, height=48)
    assert frame.image.shape == (48, 64, 3) and frame.image.dtype == np.float32
    assert frame.ids.shape == (48, 64) and frame.ids.dtype == np.int32
    assert (frame.ids >= 0).any() and frame.image.max() > 0
    assert np.isfinite(frame.t_hit[frame.ids >= 0]).all()


def test_render_refuses_missing_files_and_bad_sizes():
    with pytest.raises(kdrt.Error, match="no-such.json"):
        kdrt.load_scene("no-such.json")
    scene = kdrt.load_scene(str(ROOT / "scenes" / "lens.json"))
    with pytest.raises(ValueError):
        kdrt.render(scene, width=-1)


def test_ctrl_c_cancels_a_render():
    scene = kdrt.load_scene(str(ROOT / "scenes" / "ball-o-calypse.json"))
    timer = threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT))
    start = time.monotonic()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        kdrt.render(scene, width=1600, height=1200, samples=16)
    timer.join()
    assert time.monotonic() - start < 20  # the whole frame takes minutes
