#!/usr/bin/env python3
"""NVIDIA Warp's wp.Mesh ray queries on the meshes and rays that
`kdrt-bench rays --export DIR` wrote: Warp's own BVH (each constructor it
offers), closest hit (wp.mesh_query_ray) and any hit (wp.mesh_query_ray_anyhit).
Each answer is checked against Embree's in the export (a hit at the same
distance within 1e-4 relative; more than one ray in a thousand otherwise fails
the row), then timed two ways: the kernel alone on rays already on the device,
and from host arrays to host arrays as kdrt's intersect() and occluded() are
timed (rays uploaded; distances and faces, or the any-hit answers, read back). Medians of --runs after a warm-up.

  python3 bench/warp_rays.py --export DIR --out DIR [--device cuda:0] [--runs 5]

Writes OUT/warp.json. Needs warp-lang (PyPI) and numpy; a benchmark peer only.
"""
import argparse
import json
import os
import statistics
import sys
import time

import numpy as np
import warp as wp

MAX_T = 1.0e30  # "no limit" for Warp's queries; kdrt's and Embree's are infinite


@wp.kernel
def closest_kernel(mesh: wp.uint64, origins: wp.array(dtype=wp.vec3), directions: wp.array(dtype=wp.vec3),
                   ts: wp.array(dtype=float), faces: wp.array(dtype=int)):
    i = wp.tid()
    q = wp.mesh_query_ray(mesh, origins[i], directions[i], MAX_T)
    if q.result:
        ts[i] = q.t
        faces[i] = q.face
    else:
        ts[i] = MAX_T
        faces[i] = -1


@wp.kernel
def any_hit_kernel(mesh: wp.uint64, origins: wp.array(dtype=wp.vec3), directions: wp.array(dtype=wp.vec3),
                   hits: wp.array(dtype=wp.uint8)):
    i = wp.tid()
    if wp.mesh_query_ray_anyhit(mesh, origins[i], directions[i], MAX_T):
        hits[i] = wp.uint8(1)
    else:
        hits[i] = wp.uint8(0)


def median_ms(f, runs, device):
    f()  # warm-up: compiles and loads the kernels
    wp.synchronize_device(device)
    times = []
    for _ in range(runs):
        t0 = time.perf_counter()
        f()
        wp.synchronize_device(device)
        times.append((time.perf_counter() - t0) * 1e3)
    return statistics.median(times)


def disagreements(any_hit, answer, reference):
    """Rays whose answer is not the reference's (beyond ties in distance)."""
    if any_hit:
        return int(np.count_nonzero(answer != reference))
    hit, ref_hit = answer < MAX_T, np.isfinite(reference)
    both = hit & ref_hit
    far = np.abs(answer[both] - reference[both]) > 1e-4 * np.maximum(1.0, np.abs(reference[both]))
    return int(np.count_nonzero(hit != ref_hit) + np.count_nonzero(far))


class Queries:
    """One ray set on the device, and both queries over it."""

    def __init__(self, rays, device):
        self.device, self.n = device, len(rays)
        self.host_origins = np.ascontiguousarray(rays[:, :3])
        self.host_directions = np.ascontiguousarray(rays[:, 3:])
        self.origins = wp.array(self.host_origins, dtype=wp.vec3, device=device)
        self.directions = wp.array(self.host_directions, dtype=wp.vec3, device=device)
        self.ts = wp.empty(self.n, dtype=float, device=device)
        self.faces = wp.empty(self.n, dtype=int, device=device)
        self.hits = wp.empty(self.n, dtype=wp.uint8, device=device)

    def launch(self, mesh, any_hit, origins=None, directions=None):
        o = origins if origins is not None else self.origins
        d = directions if directions is not None else self.directions
        if any_hit:
            wp.launch(any_hit_kernel, dim=self.n, inputs=[mesh.id, o, d, self.hits], device=self.device)
        else:
            wp.launch(closest_kernel, dim=self.n, inputs=[mesh.id, o, d, self.ts, self.faces], device=self.device)

    def answer(self, any_hit):
        return self.hits.numpy() if any_hit else self.ts.numpy()

    def host_to_host(self, mesh, any_hit):
        """As a caller with numpy arrays sees it: upload, query, read back (closest: t and face)."""
        o = wp.array(self.host_origins, dtype=wp.vec3, device=self.device)
        d = wp.array(self.host_directions, dtype=wp.vec3, device=self.device)
        self.launch(mesh, any_hit, o, d)
        return self.answer(any_hit) if any_hit else (self.ts.numpy(), self.faces.numpy())


def build_mesh(vertices, triangles, constructor, device, runs):
    """Warp's BVH over the mesh: the median build's milliseconds and the mesh."""
    points = wp.array(vertices, dtype=wp.vec3, device=device)
    indices = wp.array(triangles.reshape(-1).astype(np.int32), dtype=wp.int32, device=device)
    meshes = []

    def build():
        meshes.append(wp.Mesh(points=points, indices=indices, bvh_constructor=constructor))

    ms = median_ms(build, runs, device)
    return ms, meshes[-1]


def run_input(export_dir, index, args, rows):
    vertices = np.fromfile(os.path.join(export_dir, index["vertices"]), dtype=np.float32).reshape(-1, 3)
    triangles = np.fromfile(os.path.join(export_dir, index["triangles"]), dtype=np.uint32).reshape(-1, 3)
    sets = []
    for s in index["sets"]:
        rays = np.fromfile(os.path.join(export_dir, s["file"]), dtype=np.float32).reshape(-1, 6)
        reference = {
            False: np.fromfile(os.path.join(export_dir, s["closest_t"]), dtype=np.float32),
            True: np.fromfile(os.path.join(export_dir, s["any_hit"]), dtype=np.uint8),
        }
        sets.append((s["rays"], Queries(rays, args.device), reference))
    for constructor in args.constructors:
        try:
            build_ms, mesh = build_mesh(vertices, triangles, None if constructor == "default" else constructor,
                                        args.device, 3)
        except Exception as e:  # a constructor this Warp or this device lacks
            rows.append({"input": index["input"], "constructor": constructor, "error": str(e)[:300]})
            continue
        for name, queries, reference in sets:
            for any_hit in (False, True):
                row = {"input": index["input"], "rays": name, "query": "any hit" if any_hit else "closest",
                       "count": queries.n, "constructor": constructor, "build_ms": build_ms}
                queries.launch(mesh, any_hit)
                differ = disagreements(any_hit, queries.answer(any_hit), reference[any_hit])
                row["differ"] = differ
                if differ > queries.n // 1000:
                    row["error"] = f"{differ} of {queries.n} rays differ from Embree's"
                else:
                    kernel = median_ms(lambda: queries.launch(mesh, any_hit), args.runs, args.device)
                    host = median_ms(lambda: queries.host_to_host(mesh, any_hit), args.runs, args.device)
                    row.update({"kernel_ms": kernel, "kernel_mrays_per_s": queries.n / kernel / 1e3,
                                "host_ms": host, "host_mrays_per_s": queries.n / host / 1e3})
                rows.append(row)
                print(json.dumps(row), file=sys.stderr, flush=True)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--export", required=True, help="the directory kdrt-bench rays --export wrote")
    p.add_argument("--out", required=True)
    p.add_argument("--device", default="cuda:0")
    p.add_argument("--runs", type=int, default=5)
    p.add_argument("--constructors", default="default,sah,lbvh", help="Warp's BVH constructors, comma-separated")
    args = p.parse_args()
    args.constructors = args.constructors.split(",")
    wp.config.quiet = True
    wp.init()
    indexes = sorted(f for f in os.listdir(args.export) if f.endswith(".json"))
    if not indexes:
        sys.exit(f"warp_rays: no NAME.json in {args.export}: run kdrt-bench rays --export there first")
    rows = []
    for f in indexes:
        with open(os.path.join(args.export, f)) as h:
            run_input(args.export, json.load(h), args, rows)
    device = wp.get_device(args.device)
    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, "warp.json"), "w") as h:
        json.dump({"warp_version": wp.config.version, "device": args.device, "device_name": device.name,
                   "runs": args.runs, "host_read_back": "distance and face (8 bytes a ray) or the answer (1 byte)",
                   "rows": rows}, h, indent=1)
    print(f"warp_rays: wrote {os.path.join(args.out, 'warp.json')}", file=sys.stderr)


if __name__ == "__main__":
    main()
