#!/usr/bin/env python3
"""One process against a cluster of ranks on this machine, through kdrt-render
built with -DKDRT_MPI=ON.

For each scene: `kdrt-render --threads T` against `mpirun -np N kdrt-render
--threads T/N` (the same threads in all), and `mpirun -np 1 --threads T` (the
same tiles in one rank: what tiling alone costs), in turn, medians of --rounds.
Efficiency = one process's time / the cluster's (1.0: the split costs nothing),
for the render (kdrt-render's render_ms against the cluster's, from the first
tile handed out to the last assembled) and for the whole command (mpirun's
start, loading, tree, broadcast, writing). Also rank 0's broadcast, assembly and
receive times, the tiles each rank took, and the tile size's effect on one scene.

  bench/cluster.py --render build-mpi/apps/kdrt-render/kdrt-render --out bench/results
"""
import argparse
import json
import os
import shutil
import sys
import tempfile

import benchlib


def mpirun(ranks):
    # Shared memory with its single-copy mechanism (CMA); a container that forbids
    # process_vm_readv needs --mca btl_vader_single_copy_mechanism none, and broadcasts slow down.
    cmd = ["mpirun", "--oversubscribe", "--bind-to", "none", "--mca", "btl", "self,vader", "-np", str(ranks)]
    return cmd + (["--allow-run-as-root"] if os.getuid() == 0 else [])


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--render", required=True, help="kdrt-render built with -DKDRT_MPI=ON")
    p.add_argument("--ranks", type=int, default=2)
    p.add_argument("--threads", type=int, default=os.cpu_count())
    p.add_argument("--rounds", type=int, default=5)
    p.add_argument("--size", default="800x800")
    p.add_argument("--scenes", default=",".join(benchlib.STUDY_SCENES))
    p.add_argument("--meshes", default="", help="scene files of generated meshes, comma separated")
    p.add_argument("--tile-scene", default="ball-o-calypse")
    p.add_argument("--tiles", default="16,32,64,128,256")
    p.add_argument("--quick", action="store_true", help="128x128, lens, one round: a smoke test")
    p.add_argument("--out", required=True)
    a = p.parse_args()
    if a.quick:
        a.size, a.scenes, a.tile_scene, a.tiles, a.rounds = "128x128", "lens", "lens", "32", 1
    width, height = a.size.split("x")
    work = tempfile.mkdtemp(prefix="kdrt-cluster-")
    per_rank = max(1, a.threads // a.ranks)

    def command(scene, config, tile=None):
        ranks = {"process": 0, "one rank": 1, "cluster": a.ranks}[config]
        threads = per_rank if config == "cluster" else a.threads
        cmd = [a.render, benchlib.scene_path(scene), "--width", width, "--height", height, "--threads", str(threads),
               "--stats-json", "-q", "-o", os.path.join(work, "x.png")] + (["--tile", f"{tile}x{tile}"] if tile else [])
        return (mpirun(ranks) if ranks else []) + cmd

    def measure(scene, config, tile=None):
        r = benchlib.run(command(scene, config, tile))
        stats = json.loads(r["stdout"].strip().splitlines()[-1])
        cluster = stats.get("cluster")
        return {"render_ms": cluster["render_ms"] if cluster else stats["render_ms"], "wall_ms": r["wall_ms"],
                "cluster": cluster}

    rows = []
    scenes = [s for s in a.scenes.split(",") if s] + [m for m in a.meshes.split(",") if m]
    for scene in scenes:
        configs = ["process", "one rank", "cluster"]
        runs = benchlib.in_turn(configs, a.rounds, lambda c: measure(scene, c))
        row = {"scene": os.path.basename(scene).removesuffix(".json")}
        for c in configs:
            row[c] = {k: benchlib.median(r[k] for r in runs[c]) for k in ("render_ms", "wall_ms")}
        last = runs["cluster"][-1]["cluster"]
        row["rank0"] = {k: last[k] for k in ("broadcast_ms", "broadcast_bytes", "assemble_ms", "receive_ms")}
        row["tiles_per_rank"] = [s["tiles"] for s in last["shares"]]
        rows.append(row)
        print(f"cluster: {row['scene']}: " + ", ".join(f"{c} {row[c]['render_ms']:.0f} ms" for c in configs),
              file=sys.stderr)
    tiles = []
    for t in [t for t in a.tiles.split(",") if t]:
        runs = benchlib.in_turn(["process", "cluster"], a.rounds,
                                lambda c: measure(a.tile_scene, c, t if c == "cluster" else None))
        tiles.append({"tile": int(t), "tiles": runs["cluster"][-1]["cluster"]["tiles"],
                      "process_ms": benchlib.median(r["render_ms"] for r in runs["process"]),
                      "cluster_ms": benchlib.median(r["render_ms"] for r in runs["cluster"])})
    shutil.rmtree(work)
    benchlib.write_result(a.out, "cluster", " ".join(sys.argv),
                          {"settings": {"size": a.size, "ranks": a.ranks, "threads": a.threads, "rounds": a.rounds,
                                        "tile_scene": a.tile_scene, "quick": a.quick},
                           "rows": rows, "tiles": tiles})


if __name__ == "__main__":
    main()
