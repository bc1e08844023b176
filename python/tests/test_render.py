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


def test_python_render_equals_the_command_line(tmp_path):
    """The C++ command line and kdrt.render give the same picture, ids and t."""
    render = os.environ.get("KDRT_RENDER")
    if not render:
        pytest.skip("KDRT_RENDER (the kdrt-render executable) is not set; CTest sets it")
    import subprocess

    scene_path = ROOT / "scenes" / "lens.json"
    out, ids = tmp_path / "lens.pfm", tmp_path / "lens.ids"
    subprocess.run([render, str(scene_path), "-o", str(out), "--aov-ids", str(ids), "--width", "64",
                    "--height", "48", "--device", "cpu"], check=True, capture_output=True)
    frame = kdrt.render(str(scene_path), device="cpu", width=64, height=48)
    raw = ids.read_bytes()
    cpp_ids = np.frombuffer(raw[: 64 * 48 * 4], "<i4").reshape(48, 64)
    cpp_t = np.frombuffer(raw[64 * 48 * 4:], "<f4").reshape(48, 64)
    np.testing.assert_array_equal(frame.ids, cpp_ids)
    hit = cpp_ids >= 0
    np.testing.assert_array_equal(frame.t_hit[hit], cpp_t[hit])
    # PFM: a text header of three lines, then float32 rows from the bottom row up.
    data = out.read_bytes()
    header_end = 0
    for _ in range(3):
        header_end = data.index(b"\n", header_end) + 1
    scale = float(data[:header_end].split()[3])
    pixels = np.frombuffer(data[header_end:], "<f4" if scale < 0 else ">f4").reshape(48, 64, 3)[::-1]
    np.testing.assert_array_equal(frame.image, pixels)
