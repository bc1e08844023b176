#!/usr/bin/env python3
"""Two or more kdrt-render binaries on the OpenCL device, interleaved (the
order flips every round so neither side always runs first), per scene: the
median render_ms (wall) and the median CPU time of the whole process
(user + sys). On a machine shared with other work the CPU time is the steadier
figure: it does not count the time others hold the cores.

Usage: bench/ab_opencl.py ROUNDS "SCENE ..." KDRT_RENDER_A KDRT_RENDER_B [...]
Extra kdrt-render options (e.g. --traversal ropes) go in $KDRT_AB_OPTIONS."""
import json
import os
import resource
import shlex
import statistics
import subprocess
import sys
import tempfile


def main():
    if len(sys.argv) < 5:
        sys.exit(__doc__)
    rounds, scenes, binaries = int(sys.argv[1]), sys.argv[2].split(), sys.argv[3:]
    root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    extra = shlex.split(os.environ.get("KDRT_AB_OPTIONS", ""))
    with tempfile.TemporaryDirectory(prefix="kdrt-ab-") as tmp:
        def run(binary, scene):
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            out = subprocess.run([binary, os.path.join(root, "scenes", scene + ".json"), "--device", "opencl",
                                  "--tree-cache", os.path.join(tmp, "trees"), "--stats-json",
                                  "-o", os.path.join(tmp, "out.png")] + extra,
                                 capture_output=True, text=True, check=True).stdout
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            cpu_ms = 1000 * (after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
            return json.loads(out.strip().splitlines()[-1])["render_ms"], cpu_ms

        print("| scene | " + " | ".join(f"{os.path.basename(b)} render ms / process CPU ms" for b in binaries) + " | load |")
        print("|---|" + "---:|" * (len(binaries) + 1))
        for scene in scenes:
            for b in binaries:
                run(b, scene)  # warm-up: kernel compile, tree cache
            wall = {b: [] for b in binaries}
            cpu = {b: [] for b in binaries}
            for r in range(rounds):
                for b in binaries if r % 2 == 0 else binaries[::-1]:
                    w, c = run(b, scene)
                    wall[b].append(w)
                    cpu[b].append(c)
            load = open("/proc/loadavg").read().split()[0]
            cells = [f"{statistics.median(wall[b]):.1f} / {statistics.median(cpu[b]):.0f}" for b in binaries]
            print(f"| {scene} | " + " | ".join(cells) + f" | {load} |", flush=True)


if __name__ == "__main__":
    main()
