#!/usr/bin/env python3
"""One process against a cluster of ranks on this machine, through the CLI.

For each scene: `kdrt-render --threads T` against `mpirun -np N kdrt-render
--threads T/N` (the same total threads), run in turn (A B A B ...) so both
see the same load, medians of ROUNDS. Efficiency = one process's time / the
cluster's time (1.0: the ranks lose nothing to their split). A third command,
`mpirun -np 1 --threads T`, renders the same tiles in one rank: tiles alone
change the cpu device's speed, so the cluster's own cost is the ratio to it. Both the render
time (kdrt-render's render_ms against the cluster's, from the first tile
handed out to the last frame assembled) and the whole command's wall time
(mpirun's start-up, loading, tree build, broadcast, writing) are reported,
with the CPU time each command used (user + sys, mpirun and all ranks: what
the cluster costs in work, whatever else loads the machine), and
with rank 0's broadcast and assembly times. Then the tile-size trade-off on
one scene.

Usage: bench/mpi_scaling.py KDRT_RENDER [--ranks 2] [--threads 2] [--rounds 5]
           [--size 800x800] [--mesh DIR/scene.json] [--tile-scene ball-o-calypse]
A big mesh: `kdrt-bench generate torus:1M DIR` writes DIR/*.json (BENCHMARKS.md section 8).
"""
import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENES = ["2x2x4", "insane", "purple-wall", "lens", "ball-o-calypse"]


def mpirun(ranks):
    # Shared memory with its single-copy mechanism (CMA): without it (a container that forbids
    # process_vm_readv: add --mca btl_vader_single_copy_mechanism none) big broadcasts are slower.
    cmd = ["mpirun", "--oversubscribe", "--bind-to", "none", "--mca", "btl", "self,vader", "-np", str(ranks)]
    if os.getuid() == 0:
        cmd.append("--allow-run-as-root")
    return cmd


def cpu_seconds():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run(cmd):
    """The command's last JSON line, its wall ms and its CPU seconds (mpirun's and its ranks')."""
    start, cpu = time.monotonic(), cpu_seconds()
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    wall = (time.monotonic() - start) * 1000.0
    j = json.loads(out.strip().splitlines()[-1])
    j["cpu_s"] = cpu_seconds() - cpu
    return j, wall


def main():
    p = argparse.ArgumentParser()
    p.add_argument("render")
    p.add_argument("--ranks", type=int, default=2)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--rounds", type=int, default=5)
    p.add_argument("--size", default="800x800")
    p.add_argument("--scenes", default=",".join(SCENES), help="of scenes/, comma-separated ('' for none)")
    p.add_argument("--mesh", action="append", default=[])
    p.add_argument("--tile-scene", default="ball-o-calypse")
    p.add_argument("--tiles", default="16,32,64,128,256")
    a = p.parse_args()
    w, h = a.size.split("x")
    out = tempfile.mkdtemp(prefix="kdrt-mpi-")
    scenes = [(s, os.path.join(ROOT, "scenes", s + ".json")) for s in a.scenes.split(",") if s]
    scenes += [(os.path.basename(m), m) for m in a.mesh]
    per_rank = max(1, a.threads // a.ranks)

    def single(path, extra=()):
        return run([a.render, path, "--width", w, "--height", h, "--threads", str(a.threads), "--stats-json",
                    "-o", os.path.join(out, "one.png"), *extra])

    def cluster(path, extra=(), ranks=a.ranks, threads=per_rank):
        return run(mpirun(ranks) + [a.render, path, "--width", w, "--height", h, "--threads", str(threads),
                                    "--stats-json", "-o", os.path.join(out, "mpi.png"), *extra])

    print(f"{a.size}, {a.rounds} rounds, medians; one process --threads {a.threads} against "
          f"{a.ranks} ranks --threads {per_rank}\n")
    print("| scene | render ms, 1 process | render ms, 1 rank | render ms, cluster | efficiency (render) "
          "| against 1 rank | wall ms, 1 process "
          "| wall ms, cluster | efficiency (wall) | CPU s, 1 process | CPU s, cluster | broadcast ms (bytes) "
          "| assemble ms | receive ms | tiles per rank |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|")
    for name, path in scenes:
        one_r, one_w, mpi_r, mpi_w, one_c, mpi_c, rank1_r, last = [], [], [], [], [], [], [], None
        for _ in range(a.rounds):
            j, wall = single(path)
            one_r.append(j["render_ms"])
            one_w.append(wall)
            one_c.append(j["cpu_s"])
            j, wall = cluster(path)
            mpi_r.append(j["cluster"]["render_ms"])
            mpi_w.append(wall)
            mpi_c.append(j["cpu_s"])
            # The same tiles in one rank with all the threads: the cluster's own cost, apart from what tiling does.
            rank1_r.append(cluster(path, ranks=1, threads=a.threads)[0]["cluster"]["render_ms"])
            last = j["cluster"]
        m = statistics.median
        shares = "/".join(str(s["tiles"]) for s in last["shares"])
        print(f"| {name} | {m(one_r):.0f} | {m(rank1_r):.0f} | {m(mpi_r):.0f} | {m(one_r) / m(mpi_r):.2f} | "
              f"{m(rank1_r) / m(mpi_r):.2f} | {m(one_w):.0f} | "
              f"{m(mpi_w):.0f} | {m(one_w) / m(mpi_w):.2f} | {m(one_c):.2f} | {m(mpi_c):.2f} | {last['broadcast_ms']:.1f} ({last['broadcast_bytes']}) | "
              f"{last['assemble_ms']:.1f} | {last['receive_ms']:.1f} | {shares} |", flush=True)

    path = os.path.join(ROOT, "scenes", a.tile_scene + ".json")
    print(f"\nTile size on {a.tile_scene}, {a.ranks} ranks (render ms, median of {a.rounds}; "
          f"one process --threads {a.threads} alongside)\n")
    print("| tile | tiles | render ms, cluster | efficiency | receive ms | assemble ms |")
    print("|---|---:|---:|---:|---:|---:|")
    for t in filter(None, a.tiles.split(",")):
        one_r, mpi_r, last = [], [], None
        for _ in range(a.rounds):
            one_r.append(single(path)[0]["render_ms"])
            j, _ = cluster(path, ["--tile", f"{t}x{t}"])
            mpi_r.append(j["cluster"]["render_ms"])
            last = j["cluster"]
        m = statistics.median
        print(f"| {t}x{t} | {last['tiles']} | {m(mpi_r):.0f} | {m(one_r) / m(mpi_r):.2f} | {last['receive_ms']:.1f} | "
              f"{last['assemble_ms']:.1f} |", flush=True)


if __name__ == "__main__":
    sys.exit(main())
