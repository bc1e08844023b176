#!/usr/bin/env python3
"""kdrt.RaycastingScene against Open3D's RaycastingScene and trimesh over
embreex, on the same meshes and rays: the hits are compared first (ids,
t within 1e-5 relative, counts, closest points), then each query is timed
(one warm-up call dropped, the median of --repeats) and a Markdown table
printed. Needs scripts/python-env.sh --bench.

    build-python/venv/bin/python bench/python_raycasting.py [--rays 1000000] [--threads 2]
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

import numpy as np

import kdrt


def torus(major_segments: int, minor_segments: int, R: float = 1.0, r: float = 0.35):
    """A closed torus of 2 * major * minor triangles, gently rippled so that no two hits tie."""
    u = np.linspace(0, 2 * np.pi, major_segments, endpoint=False)
    v = np.linspace(0, 2 * np.pi, minor_segments, endpoint=False)
    uu, vv = np.meshgrid(u, v, indexing="ij")
    rr = r * (1 + 0.05 * np.sin(7 * uu) * np.cos(5 * vv))
    vertices = np.stack([(R + rr * np.cos(vv)) * np.cos(uu), (R + rr * np.cos(vv)) * np.sin(uu), rr * np.sin(vv)], -1)
    i, j = np.meshgrid(np.arange(major_segments), np.arange(minor_segments), indexing="ij")
    a = i * minor_segments + j
    b = ((i + 1) % major_segments) * minor_segments + j
    c = ((i + 1) % major_segments) * minor_segments + (j + 1) % minor_segments
    d = i * minor_segments + (j + 1) % minor_segments
    faces = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    return vertices.reshape(-1, 3).astype(np.float32), faces.astype(np.uint32)


def incoherent_rays(n: int, rng) -> np.ndarray:
    origins = rng.uniform(-2, 2, (n, 3))
    targets = rng.uniform(-1.2, 1.2, (n, 3)) * [1, 1, 0.4]
    return np.concatenate([origins, targets - origins], 1).astype(np.float32)


def camera_rays(n: int) -> np.ndarray:
    side = int(np.sqrt(n))
    return kdrt.RaycastingScene.create_rays_pinhole(50, [0, 0, 0], [0.3, -2.2, 1.6], [0, 0, 1], side, side).reshape(-1, 6)


def timed(f, repeats: int) -> float:
    f()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def compare_cast(kd, o3, rays, extent, name):
    """Closest hits against Open3D's: the same geometry and primitive on
    99.99 % of rays, and t within 1e-5 relative on 99.99 % of the rays both hit.
    t is compared as a distance along the ray, relative to at least 1 % of the
    mesh's size: a hit a hair from the origin has a tiny t whose rounding is
    the coordinates', not the hit's."""
    t_k, t_o = kd["t_hit"], o3["t_hit"].numpy()
    ids_equal = (kd["primitive_ids"] == o3["primitive_ids"].numpy()) & (kd["geometry_ids"] == o3["geometry_ids"].numpy())
    both = np.isfinite(t_k) & np.isfinite(t_o)
    length = np.linalg.norm(rays[both, 3:], axis=1)
    rel = np.abs(t_k[both] - t_o[both]) * length / np.maximum(np.abs(t_o[both]) * length, 0.01 * extent)
    agree = ids_equal.mean()
    print(f"  {name}: ids agree {100 * agree:.4f} %, t max rel diff {rel.max() if rel.size else 0:.2e}, "
          f"hit rays {both.mean() * 100:.1f} %")
    return agree >= 0.9999 and (rel.size == 0 or np.quantile(rel, 0.9999) <= 1e-5)


def committed_mib(library: str, major: int, minor: int) -> float:
    """Run in a process of its own: the resident memory (MiB) one committed
    scene of the torus adds, its arrays made first (kdrt copies them in; Open3D
    keeps views of its tensors)."""
    import resource

    vertices, faces = torus(major, minor)
    ray = np.array([[0, 0, 5, 0, 0, -1]], np.float32)

    def rss_mib():
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * resource.getpagesize() / 2**20

    if library == "open3d":
        import open3d as o3d
        v, f = o3d.core.Tensor(vertices), o3d.core.Tensor(faces)
        before = rss_mib()
        scene = o3d.t.geometry.RaycastingScene(nthreads=1)
        scene.add_triangles(v, f)
        scene.cast_rays(o3d.core.Tensor(ray))
    else:
        before = rss_mib()
        scene = kdrt.RaycastingScene(nthreads=1, accel=library.split(":")[1])
        scene.add_triangles(vertices, faces)
        scene.cast_rays(ray)
    return rss_mib() - before


def memory_rows(major: int, minor: int):
    import subprocess

    rows = {}
    for library in ["open3d", "kdrt:bvh", "kdrt:kd"]:
        out = subprocess.run([sys.executable, __file__, "--memory-of", library, "--mesh", f"{major}x{minor}"],
                             check=True, capture_output=True, text=True).stdout
        rows[library] = float(out.split()[-1])
    return rows


def check(scenes, o3, o3d, ray_sets, points, vertices) -> bool:
    """The answers agree with Open3D's: ids and t of closest hits, counts,
    list sizes, distances. Printed; False when any differs beyond the targets."""
    ok = True
    extent = float(np.ptp(vertices, axis=0).max())
    od = o3.compute_distance(o3d.core.Tensor(points)).numpy()
    for name, rays in ray_sets.items():
        o3_cast = o3.cast_rays(rays)
        oc = o3.count_intersections(rays).numpy()
        sub = rays[: min(len(rays), 200_000)]
        ol = len(o3.list_intersections(sub)["t_hit"].numpy())
        for device, s in scenes.items():
            ok &= compare_cast(s.cast_rays(rays), o3_cast, rays, extent, f"cast_rays {name} {device}")
            same = (s.count_intersections(rays) == oc).mean()
            kl = len(s.list_intersections(sub)["t_hit"])
            print(f"  count_intersections {name} {device}: equal on {100 * same:.4f} % of rays; "
                  f"list_intersections: {kl} hits, Open3D {ol}")
            ok &= same >= 0.9999 and abs(kl - ol) <= 1e-4 * ol
    for device, s in scenes.items():
        # Distances agree to float rounding; the points themselves may differ
        # where a query is equally near several primitives (a shared vertex or
        # edge, the torus's axis), so they are compared by the distance they give.
        kd = s.compute_distance(points)
        kp = s.compute_closest_points(points)["points"]
        worst = max(np.abs(kd - od).max(), np.abs(np.linalg.norm(kp - points, axis=1) - od).max()) / extent
        print(f"  compute_distance / closest points {device}: max diff {worst:.1e} of the mesh's size")
        ok &= worst <= 1e-5
    return ok


def timings(scenes, o3, o3d, embree, ray_sets, points, repeats):
    """Median seconds of each query for each library: rows of {query, column: s}."""
    rows = []
    r = repeats
    for name, rays in ray_sets.items():
        rays_o3 = o3d.core.Tensor(rays)
        origins, directions = rays[:, :3].astype(np.float64), rays[:, 3:].astype(np.float64)
        cast = {"query": f"cast_rays, {name}", "Open3D": timed(lambda: o3.cast_rays(rays_o3), r),
                "trimesh+embreex": timed(lambda: embree.intersects_first(origins, directions), max(1, r // 2))}
        count = {"query": f"count_intersections, {name}", "Open3D": timed(lambda: o3.count_intersections(rays_o3), r)}
        lists = {"query": f"list_intersections, {name}", "Open3D": timed(lambda: o3.list_intersections(rays_o3), r),
                 "trimesh+embreex": timed(lambda: embree.intersects_id(origins, directions, multiple_hits=True,
                                                                       return_locations=True), 1)}
        for device, s in scenes.items():
            cast[f"kdrt {device}"] = timed(lambda: s.cast_rays(rays), r)
            count[f"kdrt {device}"] = timed(lambda: s.count_intersections(rays), r)
            lists[f"kdrt {device}"] = timed(lambda: s.list_intersections(rays), r)
        rows += [cast, count, lists]
    pts_o3 = o3d.core.Tensor(points)
    closest = {"query": "compute_closest_points", "Open3D": timed(lambda: o3.compute_closest_points(pts_o3), r)}
    for device, s in scenes.items():
        closest[f"kdrt {device}"] = timed(lambda: s.compute_closest_points(points), r)
    return rows + [closest]


def python_overhead(s, rays, threads, repeats):
    """cast_rays from Python against the bare C++ kdrt::intersect on the same rays, alternated."""
    py, cpp = [], []
    for _ in range(repeats):
        t0 = time.perf_counter()
        s.cast_rays(rays)
        py.append(time.perf_counter() - t0)
        cpp.append(s._scene._cpp_intersect_ms(rays, threads) / 1000)
    return statistics.median(py), statistics.median(cpp)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rays", type=int, default=1_000_000)
    ap.add_argument("--points", type=int, default=200_000)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--mesh", default="1000x250", help="torus segments MAJORxMINOR (2*M*m triangles)")
    ap.add_argument("--devices", default="cpu", help="kdrt devices, comma-separated (cpu,opencl)")
    ap.add_argument("--quick", action="store_true", help="tiny sizes, one repeat: a smoke test")
    ap.add_argument("--out", help="also write OUT/python.json (bench/run_all.sh)")
    ap.add_argument("--memory-of", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.quick:
        args.rays, args.points, args.repeats, args.mesh = 20_000, 5_000, 1, "100x40"
    major, minor = (int(x) for x in args.mesh.split("x"))
    if args.memory_of:
        print(committed_mib(args.memory_of, major, minor))
        return 0

    import open3d as o3d
    import trimesh

    vertices, faces = torus(major, minor)
    rng = np.random.default_rng(1)
    ray_sets = {"incoherent": incoherent_rays(args.rays, rng), "camera": camera_rays(args.rays)}
    points = rng.uniform(-1.6, 1.6, (args.points, 3)).astype(np.float32)
    print(f"torus of {len(faces)} triangles; {args.rays} rays per set; {args.points} points; "
          f"{args.threads} threads; kdrt {kdrt.__version__}, Open3D {o3d.__version__}, trimesh {trimesh.__version__}")

    o3 = o3d.t.geometry.RaycastingScene(nthreads=args.threads)
    o3.add_triangles(o3d.core.Tensor(vertices), o3d.core.Tensor(faces))
    t0 = time.perf_counter()
    o3.cast_rays(o3d.core.Tensor(ray_sets["camera"][:1]))
    commits = {"Open3D": time.perf_counter() - t0}
    embree = trimesh.ray.ray_pyembree.RayMeshIntersector(trimesh.Trimesh(vertices=vertices, faces=faces, process=False))
    scenes = {}
    for device in args.devices.split(","):
        s = kdrt.RaycastingScene(nthreads=args.threads, device=device)
        s.add_triangles(vertices, faces)
        t0 = time.perf_counter()
        s.cast_rays(ray_sets["camera"][:1])
        commits[f"kdrt {device}"] = time.perf_counter() - t0
        print(f"kdrt {device} ({s.device}): commit {1000 * commits[f'kdrt {device}']:.0f} ms")
        scenes[device] = s

    if not check(scenes, o3, o3d, ray_sets, points, vertices):
        print("the results differ: not timing", file=sys.stderr)
        return 1
    rows = timings(scenes, o3, o3d, embree, ray_sets, points, args.repeats)
    overhead = {name: python_overhead(scenes[next(iter(scenes))], rays, args.threads, args.repeats)
                for name, rays in ray_sets.items()}
    memory = memory_rows(major, minor)

    columns = ["Open3D", "trimesh+embreex"] + [f"kdrt {d}" for d in scenes]
    print("\n| query | " + " | ".join(f"{c} (ms)" for c in columns) + " | Open3D / kdrt |")
    print("|---|" + "---|" * (len(columns) + 1))
    first = f"kdrt {next(iter(scenes))}"
    for row in rows:
        cells = [f"{1000 * row[c]:.1f}" if c in row else "-" for c in columns]
        print(f"| {row['query']} | " + " | ".join(cells) + f" | {row['Open3D'] / row[first]:.2f}x |")
    for name, (py, cpp) in overhead.items():
        print(f"Python overhead, cast_rays {name}: {1000 * py:.1f} ms against {1000 * cpp:.1f} ms in C++ "
              f"({100 * (py / cpp - 1):+.1f} %)")
    print("committed scene, MiB: " + ", ".join(f"{k} {v:.0f}" for k, v in memory.items()))
    if args.out:
        sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
        import benchlib

        benchlib.write_result(args.out, "python", sys.argv, {
            "settings": {"triangles": len(faces), "rays": args.rays, "points": args.points,
                         "threads": args.threads, "repeats": args.repeats, "kdrt": kdrt.__version__,
                         "open3d": o3d.__version__, "trimesh": trimesh.__version__,
                         "devices": {d: s.device for d, s in scenes.items()}},
            "columns": columns, "rows": rows, "commit_s": commits,
            "overhead": {k: {"python_s": v[0], "cpp_s": v[1]} for k, v in overhead.items()},
            "memory_mib": memory})
    return 0


if __name__ == "__main__":
    sys.exit(main())
