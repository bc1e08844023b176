#!/usr/bin/env python3
"""The kd-tree against the BVH in whole Whitted frames: kdrt-render --accel kd
and --accel bvh on the five scenes and the generated meshes, on every device
given. Per scene, device and structure: the structure's build (build_ms), the
frame's render_ms (no build, compile or write), bytes per object, medians of
--rounds taken in turn. A device that cannot trace a structure (kdrt-render
fails) gets a row saying why.

  bench/structures.py --render build/apps/kdrt-render/kdrt-render --meshes DIR/a.json,DIR/b.json --out bench/results
"""
import argparse
import os
import shutil
import sys
import tempfile

import benchlib

SCENES = "2x2x4,insane,purple-wall,lens,ball-o-calypse"


def structure_bytes(stats):
    s = stats.get("tree_stats") or stats.get("bvh_stats")
    return s["bytes_per_object"]["total"] if s else None


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--render", required=True, help="kdrt-render")
    p.add_argument("--devices", default="cpu,opencl")
    p.add_argument("--scenes", default=SCENES, help="scene names or files")
    p.add_argument("--meshes", default="", help="generated mesh scene files (kdrt-bench generate), comma-separated")
    p.add_argument("--size", default="500x500")
    p.add_argument("--rounds", type=int, default=5)
    p.add_argument("--quick", action="store_true", help="128x128, one round: a smoke test")
    p.add_argument("--out", required=True)
    a = p.parse_args()
    if a.quick:
        a.size, a.rounds = "128x128", 1
    width, height = a.size.split("x")
    work = tempfile.mkdtemp(prefix="kdrt-structures-")
    env = dict(os.environ, KDRT_KERNEL_CACHE=os.path.join(work, "kernels"))
    configs = [(d, accel) for d in a.devices.split(",") for accel in ("kd", "bvh")]
    rows = []
    for scene in [s for s in (a.scenes.split(",") + a.meshes.split(",")) if s]:
        label = os.path.splitext(os.path.basename(scene))[0]  # a mesh file's scene has no name of its own
        def measure(config):
            device, accel = config
            args = ["--device", device, "--accel", accel, "--tree-stats", "--width", width, "--height", height,
                    "-o", os.path.join(work, "x.png")]
            return benchlib.render(a.render, scene, args, env)

        usable = []
        for c in configs:
            try:
                measure(c)  # warm-up: kernels compiled and cached
                usable.append(c)
            except RuntimeError as e:
                rows.append({"scene": label, "device": c[0], "accel": c[1], "error": str(e)[-300:]})
                print(f"structures: {scene} {c}: {e}", file=sys.stderr)
        for (device, accel), runs in benchlib.in_turn(usable, a.rounds, measure).items():
            rows.append({"scene": label, "device": device, "device_name": runs[0]["device"],
                         "accel": accel, "objects_bytes": structure_bytes(runs[0]),
                         "build_ms": benchlib.median(r["build_ms"] for r in runs),
                         "render_ms": benchlib.median(r["render_ms"] for r in runs),
                         "mrays_per_s": benchlib.median(r["mrays_per_s"] for r in runs)})
            print(f"structures: {scene} {device} {accel}: build {rows[-1]['build_ms']:.1f} ms, "
                  f"render {rows[-1]['render_ms']:.1f} ms", file=sys.stderr)
    shutil.rmtree(work)
    benchlib.write_result(a.out, "structures", " ".join(sys.argv),
                          {"settings": {"size": a.size, "rounds": a.rounds, "quick": a.quick}, "rows": rows})


if __name__ == "__main__":
    main()
