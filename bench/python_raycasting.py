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


def compare_cast(kd, o3, name):
    t_k, t_o = kd["t_hit"], o3["t_hit"].numpy()
    ids_equal = (kd["primitive_ids"] == o3["primitive_ids"].numpy()) & (kd["geometry_ids"] == o3["geometry_ids"].numpy())
    both = np.isfinite(t_k) & np.isfinite(t_o)
    rel = np.abs(t_k[both] - t_o[both]) / np.maximum(np.abs(t_o[both]), 1e-30)
    agree = ids_equal.mean()
    print(f"  {name}: ids agree {100 * agree:.4f} %, t max rel diff {rel.max() if rel.size else 0:.2e}, "
          f"hit rays {both.mean() * 100:.1f} %")
    return agree >= 0.9999 and (rel.size == 0 or np.quantile(rel, 0.9999) <= 1e-5)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rays", type=int, default=1_000_000)
    ap.add_argument("--points", type=int, default=200_000)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--mesh", default="1000x250", help="torus segments MAJORxMINOR (2*M*m triangles)")
    ap.add_argument("--devices", default="cpu", help="kdrt devices, comma-separated (cpu,opencl)")
    args = ap.parse_args()

    import open3d as o3d
    import trimesh

    major, minor = (int(x) for x in args.mesh.split("x"))
    vertices, faces = torus(major, minor)
    rng = np.random.default_rng(1)
    ray_sets = {"incoherent": incoherent_rays(args.rays, rng), "camera": camera_rays(args.rays)}
    points = rng.uniform(-1.6, 1.6, (args.points, 3)).astype(np.float32)
    print(f"torus of {len(faces)} triangles; {args.rays} rays per set; {args.points} points; "
          f"{args.threads} threads; kdrt {kdrt.__version__}, Open3D {o3d.__version__}, trimesh {trimesh.__version__}")

    o3 = o3d.t.geometry.RaycastingScene(nthreads=args.threads)
    o3.add_triangles(o3d.core.Tensor(vertices), o3d.core.Tensor(faces))
    tm = trimesh.Trimesh(vertices=vertices, faces=faces, process=False)
    embree = trimesh.ray.ray_pyembree.RayMeshIntersector(tm)
    scenes = {}
    for device in args.devices.split(","):
        s = kdrt.RaycastingScene(nthreads=args.threads, device=device)
        s.add_triangles(vertices, faces)
        t0 = time.perf_counter()
        s.cast_rays(ray_sets["camera"][:1])
        print(f"kdrt {device} ({s.device}): commit {1000 * (time.perf_counter() - t0):.0f} ms")
        scenes[device] = s

    # Check, then time.
    ok = True
    for name, rays in ray_sets.items():
        o3_cast = o3.cast_rays(rays)
        for device, s in scenes.items():
            ok &= compare_cast(s.cast_rays(rays), o3_cast, f"cast_rays {name} {device}")
        if "cpu" in scenes:
            s = scenes["cpu"]
            kc, oc = s.count_intersections(rays), o3.count_intersections(rays).numpy()
            same = (kc == oc).mean()
            print(f"  count_intersections {name}: equal on {100 * same:.4f} % of rays")
            ok &= same >= 0.9999
            sub = rays[: min(len(rays), 200_000)]
            kl, ol = s.list_intersections(sub), o3.list_intersections(sub)
            print(f"  list_intersections {name}: {len(kl['t_hit'])} hits, Open3D {len(ol['t_hit'].numpy())}")
            ok &= abs(len(kl["t_hit"]) - len(ol["t_hit"].numpy())) <= 1e-4 * len(ol["t_hit"].numpy())
    if "cpu" in scenes:
        # Distances agree to float rounding; the points themselves may differ
        # where a query is equally near several primitives (a shared vertex or
        # edge, the torus's axis), so they are compared by the distance they give.
        extent = float(np.ptp(vertices, axis=0).max())
        od = o3.compute_distance(o3d.core.Tensor(points)).numpy()
        for device, s in scenes.items():
            kd = s.compute_distance(points)
            kp = s.compute_closest_points(points)["points"]
            via_point = np.linalg.norm(kp - points, axis=1)
            worst = max(np.abs(kd - od).max(), np.abs(via_point - od).max()) / extent
            print(f"  compute_distance / closest points {device}: max diff {worst:.1e} of the mesh's size")
            ok &= worst <= 1e-5
    if not ok:
        print("the results differ: not timing", file=sys.stderr)
        return 1

    rows = []
    r = args.repeats
    for name, rays in ray_sets.items():
        rays_o3 = o3d.core.Tensor(rays)
        origins, directions = rays[:, :3].astype(np.float64), rays[:, 3:].astype(np.float64)
        row = {"query": f"cast_rays, {name}"}
        row["Open3D"] = timed(lambda: o3.cast_rays(rays_o3), r)
        row["trimesh+embreex"] = timed(lambda: embree.intersects_first(origins, directions), max(1, r // 2))
        for device, s in scenes.items():
            row[f"kdrt {device}"] = timed(lambda: s.cast_rays(rays), r)
        rows.append(row)
        if "cpu" in scenes:
            s = scenes["cpu"]
            row = {"query": f"count_intersections, {name}", "Open3D": timed(lambda: o3.count_intersections(rays_o3), r)}
            row["kdrt cpu"] = timed(lambda: s.count_intersections(rays), r)
            rows.append(row)
            row = {"query": f"list_intersections, {name}", "Open3D": timed(lambda: o3.list_intersections(rays_o3), r)}
            row["trimesh+embreex"] = timed(
                lambda: embree.intersects_id(origins, directions, multiple_hits=True, return_locations=True), 1)
            row["kdrt cpu"] = timed(lambda: s.list_intersections(rays), r)
            rows.append(row)
            cpp = statistics.median(s._scene._cpp_intersect_ms(rays, args.threads) for _ in range(r)) / 1000
            py = timed(lambda: s.cast_rays(rays), r)
            print(f"  Python overhead, cast_rays {name}: {py * 1000:.1f} ms against the C++ call's "
                  f"{cpp * 1000:.1f} ms ({100 * (py / cpp - 1):+.1f} %)")
    if "cpu" in scenes:
        pts_o3 = o3d.core.Tensor(points)
        row = {"query": "compute_closest_points", "Open3D": timed(lambda: o3.compute_closest_points(pts_o3), r)}
        row["kdrt cpu"] = timed(lambda: scenes["cpu"].compute_closest_points(points), r)
        rows.append(row)

    columns = ["Open3D", "trimesh+embreex"] + [f"kdrt {d}" for d in scenes]
    print()
    print("| query | " + " | ".join(f"{c} (ms)" for c in columns) + " | kdrt cpu / Open3D |")
    print("|---|" + "---|" * (len(columns) + 1))
    for row in rows:
        cells = [f"{1000 * row[c]:.1f}" if c in row else "-" for c in columns]
        speed = f"{row['Open3D'] / row['kdrt cpu']:.2f}x" if "kdrt cpu" in row else "-"
        print(f"| {row['query']} | " + " | ".join(cells) + f" | {speed} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
