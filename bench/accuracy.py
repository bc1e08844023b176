#!/usr/bin/env python3
"""What each accuracy knob costs in time and buys in error, through kdrt-render.

Each setting changes one thing from the default (float, watertight triangles,
careful spheres, scale-aware self-intersection, the scene's depth, 1 sample);
`all-cheap` takes the three cheap tests at once. The reference is the cpu device
in double precision with the robust tests and --reference-samples samples per
pixel. Errors are on the displayed values (clamped to [0, 1]): RMSE, the largest
channel error, and the share of camera rays whose object differs from the
reference's (1 sample). Render times are medians of --runs after a warm-up.
The scenes: the study's five and the hard cases of scenes/hard/.

  bench/accuracy.py --render build/apps/kdrt-render/kdrt-render --out bench/results
"""
import argparse
import math
import os
import shutil
import sys
import tempfile
from array import array

import benchlib

SETTINGS = {
    "default": [],
    "double": ["--precision", "double"],
    "moller": ["--triangle-test", "moller"],
    "textbook-sphere": ["--sphere-test", "textbook"],
    "fixed-eps-1e-4": ["--self-intersection", "fixed", "--epsilon", "1e-4"],
    "all-cheap": ["--triangle-test", "moller", "--sphere-test", "textbook", "--self-intersection", "fixed"],
    "depth-4": ["--max-depth", "4"],
    "spp-4": ["--samples", "4"],
    "spp-16": ["--samples", "16"],
}
SCENES = benchlib.STUDY_SCENES + ["hard/lens-moved-1e5", "hard/insane-shrunk-1e-3", "hard/inside-sphere"]


def read_pfm(path):
    """A PFM image as a flat array of floats (bottom row first, as stored; only compared with another)."""
    with open(path, "rb") as f:
        if f.readline().strip() != b"PF":
            raise ValueError(f"{path}: not an RGB PFM")
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        data = array("f")
        data.frombytes(f.read(w * h * 12))
    if (scale < 0) != (sys.byteorder == "little"):
        data.byteswap()
    return data


def read_ids(path):
    """An id map (FORMAT.md): W*H little-endian int32 ids, then W*H float32 distances; the ids."""
    with open(path, "rb") as f:
        raw = f.read()
    ids = array("i")
    ids.frombytes(raw[: len(raw) // 2])
    if sys.byteorder == "big":
        ids.byteswap()
    return ids


def errors(ref, img):
    """RMSE and largest error of the displayed (clamped) values."""
    clamp = lambda v: min(max(v, 0.0), 1.0)
    diffs = [clamp(a) - clamp(b) for a, b in zip(ref, img)]
    return math.sqrt(sum(d * d for d in diffs) / max(1, len(diffs))), max((abs(d) for d in diffs), default=0.0)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--render", required=True, help="kdrt-render")
    p.add_argument("--devices", default="cpu,opencl")
    p.add_argument("--scenes", default=",".join(SCENES))
    p.add_argument("--size", type=int, default=250, help="square image side")
    p.add_argument("--runs", type=int, default=3)
    p.add_argument("--reference-samples", type=int, default=16)
    p.add_argument("--quick", action="store_true", help="48x48, two scenes, 1 run, 4-sample references: a smoke test")
    p.add_argument("--out", required=True)
    a = p.parse_args()
    if a.quick:
        a.size, a.runs, a.reference_samples = 48, 1, 4
        a.scenes = "lens,hard/insane-shrunk-1e-3" if a.scenes == p.get_default("scenes") else a.scenes
    work = tempfile.mkdtemp(prefix="kdrt-accuracy-")
    env = dict(os.environ, KDRT_KERNEL_CACHE=os.path.join(work, "kernels"))
    size = ["--width", str(a.size), "--height", str(a.size)]
    rows = []
    for scene in a.scenes.split(","):
        ref_img, ref_ids = os.path.join(work, "ref.pfm"), os.path.join(work, "ref.ids")
        benchlib.render(a.render, scene, size + ["--device", "cpu", "--precision", "double", "--samples",
                                                  str(a.reference_samples), "-o", ref_img], env)
        benchlib.render(a.render, scene, size + ["--device", "cpu", "--precision", "double", "--aov-ids", ref_ids], env)
        reference, reference_ids = read_pfm(ref_img), read_ids(ref_ids)
        for device in a.devices.split(","):
            for name, options in SETTINGS.items():
                args = size + ["--device", device] + options
                img, ids = os.path.join(work, "img.pfm"), os.path.join(work, "img.ids")
                benchlib.render(a.render, scene, args + ["-o", img, "--aov-ids", ids], env)  # warm-up, the picture
                ms = benchlib.median(benchlib.render(a.render, scene, args, env)["render_ms"] for _ in range(a.runs))
                rmse, max_error = errors(reference, read_pfm(img))
                camera = read_ids(ids)  # with several samples a pixel's id is one of its rays': not compared
                differ = None if "--samples" in options else \
                    sum(1 for x, y in zip(camera, reference_ids) if x != y) / max(1, len(camera))
                rows.append({"scene": os.path.basename(scene), "device": device, "setting": name, "render_ms": ms,
                             "rmse": rmse, "max_error": max_error, "ids_differ": differ})
                print(f"accuracy: {scene} {device} {name}: {ms:.1f} ms, RMSE {rmse:.5f}", file=sys.stderr)
    shutil.rmtree(work)
    benchlib.write_result(a.out, "accuracy", " ".join(sys.argv),
                          {"settings": {"size": a.size, "runs": a.runs, "reference_samples": a.reference_samples,
                                        "options": SETTINGS, "quick": a.quick},
                           "rows": rows})


if __name__ == "__main__":
    main()
