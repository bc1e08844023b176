"""Shared fixtures: the devices the suite runs on, and small meshes with
answers computed independently in numpy."""

import os

import numpy as np
import pytest

import kdrt


def _devices():
    devices = ["cpu"]
    if os.environ.get("KDRT_TEST_OPENCL") == "1" and any(d["id"] != "cpu" for d in kdrt.list_devices()):
        devices.append("opencl")
    return devices


DEVICES = _devices()


@pytest.fixture(params=DEVICES)
def device(request):
    return request.param


@pytest.fixture(params=["bvh", "kd"])
def accel(request):
    """The acceleration structure: both answer every query the same."""
    return request.param


def box_mesh(lo=(0.0, 0.0, 0.0), hi=(1.0, 1.0, 1.0)):
    """A closed, outward-wound box of 12 triangles."""
    lo, hi = np.asarray(lo, np.float32), np.asarray(hi, np.float32)
    corners = np.array([[(i >> a) & 1 for a in range(3)] for i in range(8)], np.float32)
    vertices = lo + corners * (hi - lo)
    faces = np.array(
        [[0, 2, 1], [1, 2, 3], [4, 5, 6], [5, 7, 6], [0, 1, 4], [1, 5, 4],
         [2, 6, 3], [3, 6, 7], [0, 4, 2], [2, 4, 6], [1, 3, 5], [3, 7, 5]],
        np.uint32,
    )
    return vertices, faces


def sphere_mesh(n=24, radius=1.0, center=(0.0, 0.0, 0.0)):
    """A closed UV sphere of 2 n (n - 1) triangles."""
    rings, segments = n, 2 * n
    vertices = [[0, 0, radius]]
    for i in range(1, rings):
        theta = np.pi * i / rings
        for j in range(segments):
            phi = 2 * np.pi * j / segments
            vertices.append([radius * np.sin(theta) * np.cos(phi), radius * np.sin(theta) * np.sin(phi),
                             radius * np.cos(theta)])
    vertices.append([0, 0, -radius])
    faces = []
    for j in range(segments):
        faces.append([0, 1 + j, 1 + (j + 1) % segments])
    for i in range(rings - 2):
        a, b = 1 + i * segments, 1 + (i + 1) * segments
        for j in range(segments):
            k = (j + 1) % segments
            faces.append([a + j, b + j, b + k])
            faces.append([a + j, b + k, a + k])
    last = len(vertices) - 1
    base = 1 + (rings - 2) * segments
    for j in range(segments):
        faces.append([base + j, last, base + (j + 1) % segments])
    return (np.asarray(vertices, np.float32) + np.asarray(center, np.float32)), np.asarray(faces, np.uint32)


def all_hits_numpy(vertices, faces, rays):
    """Every (t, triangle) of each ray by Moller-Trumbore in float64: the oracle."""
    v0, v1, v2 = (vertices[faces[:, k]].astype(np.float64) for k in range(3))
    e1, e2 = v1 - v0, v2 - v0
    out = []
    for r in rays.astype(np.float64):
        o, d = r[:3], r[3:]
        p = np.cross(d, e2)
        det = np.einsum("ij,ij->i", e1, p)
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / det
            s = o - v0
            u = np.einsum("ij,ij->i", s, p) * inv
            q = np.cross(s, e1)
            v = (q @ d) * inv
            t = np.einsum("ij,ij->i", e2, q) * inv
        ok = (np.abs(det) > 1e-12) & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
        idx = np.nonzero(ok)[0]
        out.append(sorted(zip(t[idx].tolist(), idx.tolist())))
    return out


def distances_numpy(vertices, faces, points):
    """Each point's distance to the nearest triangle, in float64: the oracle.
    A triangle's nearest point is the nearest of its plane's foot (when inside
    it) and the nearest points of its three edges."""
    p = points.astype(np.float64)[:, None, :]
    a, b, c = (vertices[faces[:, k]].astype(np.float64)[None] for k in range(3))

    def to_segment(s0, s1):
        d = s1 - s0
        t = np.clip(np.einsum("pti,pti->pt", p - s0, np.broadcast_to(d, (p.shape[0],) + d.shape[1:]))
                    / np.einsum("ti,ti->t", d[0], d[0]), 0.0, 1.0)
        return np.linalg.norm(p - (s0 + t[..., None] * d), axis=-1)

    best = np.minimum(np.minimum(to_segment(a, b), to_segment(b, c)), to_segment(c, a))
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    height = np.einsum("pti,pti->pt", p - a, np.broadcast_to(n, (p.shape[0],) + n.shape[1:]))
    foot = p - height[..., None] * n
    inside = np.ones(height.shape, bool)
    for s0, s1 in ((a, b), (b, c), (c, a)):
        inside &= np.einsum("pti,pti->pt", np.cross(s1 - s0, foot - s0), np.broadcast_to(n, foot.shape)) >= 0
    best = np.where(inside, np.minimum(best, np.abs(height)), best)
    return best.min(axis=1)
