#!/usr/bin/env python3
"""Whole processes, start to PNG: kdrt-render (each device), the Embree-based
`kdrt-bench embree-render` (same loader, shading and PNG writer) and POV-Ray 3.7
(the scene written in its language by `kdrt-bench povray`), in turn, medians of
--rounds after a warm-up (kdrt's kernels cached, its tree built in every run).
A 1x1 render of each gives the fixed cost (start-up, loading, the tree, writing)
that a frame pays whatever its size. Also each process's peak memory, and
POV-Ray's picture against kdrt's (RMSE: a check that the scenes agree, not a
comparison of quality). Meshes (`kdrt-bench generate`) go without POV-Ray.

  bench/processes.py --render build/apps/kdrt-render/kdrt-render --bench build/bench/kdrt-bench --out bench/results
"""
import argparse
import math
import os
import shutil
import sys
import tempfile
from array import array

import benchlib

POVRAY_OPTIONS = ["-D", "-A", "-GA", "File_Gamma=1.0"]  # no display, no anti-aliasing, quiet, linear output


def read_ppm(path):
    """A binary PPM (P6, 8-bit) as a flat array of values in [0, 1]."""
    with open(path, "rb") as f:
        data = f.read()
    fields, pos = [], 0
    while len(fields) < 4:  # magic, width, height, maxval; comments start with '#'
        while data[pos:pos + 1].isspace():
            pos += 1
        if data[pos:pos + 1] == b"#":
            pos = data.index(b"\n", pos)
            continue
        end = pos
        while not data[end:end + 1].isspace():
            end += 1
        fields.append(data[pos:end])
        pos = end
    w, h, maxval = int(fields[1]), int(fields[2]), int(fields[3])
    return array("d", (v / maxval for v in data[pos + 1:pos + 1 + 3 * w * h]))


def rmse(a, b):
    return math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b)) / max(1, len(a))) if len(a) == len(b) else None


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--render", required=True, help="kdrt-render")
    p.add_argument("--bench", required=True, help="kdrt-bench (its povray and embree-render commands)")
    p.add_argument("--povray", default="povray")
    p.add_argument("--devices", default="cpu,opencl,cpu+kd",
                   help="kdrt-render devices (with the default structure, the BVH); DEVICE+kd renders with --accel kd")
    p.add_argument("--scenes", default=",".join(benchlib.STUDY_SCENES))
    p.add_argument("--meshes", default="", help="scene files of generated meshes, comma separated")
    p.add_argument("--size", type=int, default=500, help="square image side")
    p.add_argument("--rounds", type=int, default=5)
    p.add_argument("--quick", action="store_true", help="64x64, one round: a smoke test")
    p.add_argument("--out", required=True)
    a = p.parse_args()
    if a.quick:
        a.size, a.rounds = 64, 1
    work = tempfile.mkdtemp(prefix="kdrt-processes-")
    env = dict(os.environ, KDRT_KERNEL_CACHE=os.path.join(work, "kernels"), POCL_CACHE_DIR=os.path.join(work, "pocl"))
    have_povray = shutil.which(a.povray) is not None
    devices = [d for d in a.devices.split(",") if d]
    inputs = [(s, benchlib.scene_path(s), True) for s in a.scenes.split(",") if s]
    inputs += [(os.path.basename(m).removesuffix(".json"), m, False) for m in a.meshes.split(",") if m]
    rows = []
    for name, path, study in inputs:
        png = os.path.join(work, name + ".png")

        def command(program, side, out=png, povray_format="+FN"):
            if program == "povray":
                pov = os.path.join(work, f"{name}-{side}.pov")
                if not os.path.exists(pov):
                    benchlib.run([a.bench, "povray", path, pov, "--size", f"{side}x{side}"])
                return [a.povray, "+I" + pov, "+O" + out, f"+W{side}", f"+H{side}", povray_format, *POVRAY_OPTIONS]
            if program == "embree":
                return [a.bench, "embree-render", path, "-o", out] + (["--size", f"{side}x{side}"] if side else [])
            size = ["--width", str(side), "--height", str(side)] if side else []  # meshes: their own size
            device, _, accel = program.partition("+")
            return [a.render, path, "--device", device, "-q", "-o", out, *size] + (["--accel", accel] if accel else [])

        programs = [*devices, "embree"] + (["povray"] if study and have_povray else [])
        sides = [a.size, 1] if study else [0]
        configs = [(prog, side) for prog in programs for side in sides]
        for c in configs:
            benchlib.run(command(*c), env)  # warm-up: kernels compiled and cached, files in the page cache
        runs = benchlib.in_turn(configs, a.rounds, lambda c: benchlib.run(command(*c), env))
        row = {"input": name, "size": a.size if study else None}
        for (prog, side), rs in runs.items():
            key = prog if side != 1 else prog + "_1x1"
            row[key] = {"wall_ms": benchlib.median(r["wall_ms"] for r in rs),
                        "cpu_s": benchlib.median(r["cpu_s"] for r in rs),
                        "peak_rss_mib": max(r["peak_rss_mib"] for r in rs)}
        if "povray" in programs:  # the pictures as 8-bit PPM, once, outside the timing
            pov_ppm, kdrt_ppm = os.path.join(work, "pov.ppm"), os.path.join(work, "kdrt.ppm")
            benchlib.run(command("povray", a.size, pov_ppm, "+FP"), env)
            benchlib.run(command("cpu", a.size, kdrt_ppm), env)
            row["povray_rmse"] = rmse(read_ppm(pov_ppm), read_ppm(kdrt_ppm))
        print(f"processes: {name}: " + ", ".join(f"{k} {v['wall_ms']:.0f} ms" for k, v in row.items()
                                                 if isinstance(v, dict)), file=sys.stderr)
        rows.append(row)
    shutil.rmtree(work)
    benchlib.write_result(a.out, "processes", " ".join(sys.argv),
                          {"settings": {"size": a.size, "rounds": a.rounds, "devices": devices,
                                        "povray_options": POVRAY_OPTIONS, "quick": a.quick},
                           "rows": rows})


if __name__ == "__main__":
    main()
