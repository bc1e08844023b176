#!/usr/bin/env python3
"""Several devices in one process against each alone: kdrt-render --device cpu,
each OpenCL device, and all of them together (`--device cpu,opencl`: tiles that
each device pulls when it has finished one) with several tile sizes. The
frame's render_ms (no tree build, kernel compile or writing), medians of
--rounds taken in turn, and each device's share of the pixels.

  bench/devices.py --render build/apps/kdrt-render/kdrt-render --out bench/results
"""
import argparse
import os
import shutil
import sys
import tempfile

import benchlib


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--render", required=True, help="kdrt-render")
    p.add_argument("--devices", default="cpu,opencl", help="the devices, alone and together")
    p.add_argument("--scenes", default="ball-o-calypse,lens")
    p.add_argument("--size", default="800x600")
    p.add_argument("--tiles", default="16,32,64,128")
    p.add_argument("--rounds", type=int, default=5)
    p.add_argument("--quick", action="store_true", help="128x96, tiles 32, one round: a smoke test")
    p.add_argument("--out", required=True)
    a = p.parse_args()
    if a.quick:
        a.size, a.tiles, a.rounds = "128x96", "32", 1
    width, height = a.size.split("x")
    work = tempfile.mkdtemp(prefix="kdrt-devices-")
    env = dict(os.environ, KDRT_KERNEL_CACHE=os.path.join(work, "kernels"))
    devices = a.devices.split(",")
    configs = [(d, None) for d in devices] + [(a.devices, t) for t in a.tiles.split(",")]
    rows = []
    for scene in a.scenes.split(","):
        def measure(config):
            device, tile = config
            args = ["--device", device, "--width", width, "--height", height, "-o", os.path.join(work, "x.png")]
            return benchlib.render(a.render, scene, args + (["--tile", tile] if tile else []), env)

        for c in configs:
            measure(c)  # warm-up: kernels compiled and cached
        for (device, tile), runs in benchlib.in_turn(configs, a.rounds, measure).items():
            shares = {}
            for r in runs:
                total = sum(s["pixels"] for s in r.get("device_shares") or []) or 1
                for s in r.get("device_shares") or []:
                    shares.setdefault(s["device"], []).append(s["pixels"] / total)
            rows.append({"scene": scene, "devices": device, "tile": int(tile) if tile else None,
                         "render_ms": benchlib.median(r["render_ms"] for r in runs),
                         "shares": {d: benchlib.median(v) for d, v in shares.items()}})
            print(f"devices: {scene} {device} {tile or ''}: {rows[-1]['render_ms']:.1f} ms", file=sys.stderr)
    shutil.rmtree(work)
    benchlib.write_result(a.out, "devices", " ".join(sys.argv),
                          {"settings": {"size": a.size, "rounds": a.rounds, "quick": a.quick}, "rows": rows})


if __name__ == "__main__":
    main()
