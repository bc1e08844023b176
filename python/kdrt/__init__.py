"""kdrt in Python: ray queries and rendering on every device kdrt runs on.

``kdrt.RaycastingScene`` has Open3D 0.20's ``open3d.t.geometry.RaycastingScene``
interface (names, shapes, dtypes, conventions) on numpy arrays, so that code
written for Open3D runs by changing the import; it adds a ``device`` ("cpu",
"opencl", "opencl:gpu", ...; kdrt.list_devices()) and ``add_spheres``.
``kdrt.load_scene`` and ``kdrt.render`` render scene and model files into
numpy arrays. See docs/PYTHON.md.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Dict, Optional

import numpy as np

from . import _kdrt
from ._kdrt import INVALID_ID, Error, Scene, __version__, list_devices, load_scene

__all__ = [
    "INVALID_ID",
    "Error",
    "Frame",
    "RaycastingScene",
    "Scene",
    "__version__",
    "list_devices",
    "load_scene",
    "render",
]


def _as_array(value: Any, dtype: np.dtype, last: int, name: str) -> np.ndarray:
    """`value` as a C-contiguous array of `dtype` with shape (..., last).

    Arrays of the right dtype are used in place when contiguous (copied once
    when not); Open3D tensors are taken through .numpy(); any other dtype is
    refused with ValueError, as Open3D refuses it.
    """
    if hasattr(value, "numpy") and not isinstance(value, np.ndarray):
        value = value.numpy()
    array = np.asarray(value) if isinstance(value, np.ndarray) else np.asarray(value, dtype=dtype)
    if array.dtype != dtype:
        raise ValueError(f"{name} must be {np.dtype(dtype).name}, got {array.dtype}")
    if array.ndim < 1 or array.shape[-1] != last:
        raise ValueError(f"{name} must have shape (..., {last}), got {array.shape}")
    return np.ascontiguousarray(array)


def _triangle_indices(value: Any) -> np.ndarray:
    """Triangle indices as uint32 (M, 3): unsigned or non-negative integers of any width."""
    if hasattr(value, "numpy") and not isinstance(value, np.ndarray):
        value = value.numpy()
    array = np.asarray(value)
    if array.dtype == np.uint32:
        return _as_array(array, np.uint32, 3, "triangle_indices")
    if not np.issubdtype(array.dtype, np.integer):
        raise ValueError(f"triangle_indices must be integers (uint32), got {array.dtype}")
    if array.size and (array.min() < 0 or array.max() > 0xFFFFFFFE):
        raise ValueError("triangle_indices must be in [0, 2^32 - 2]")
    return _as_array(array.astype(np.uint32), np.uint32, 3, "triangle_indices")


def _mesh_arrays(mesh: Any):
    """Vertices and faces of a mesh object: trimesh (vertices, faces), Open3D's
    tensor mesh (vertex.positions, triangle.indices) or legacy mesh (vertices, triangles)."""
    if hasattr(mesh, "vertex") and hasattr(mesh, "triangle"):
        return mesh.vertex.positions, mesh.triangle.indices
    if hasattr(mesh, "vertices") and hasattr(mesh, "faces"):
        return mesh.vertices, mesh.faces
    if hasattr(mesh, "vertices") and hasattr(mesh, "triangles"):
        return mesh.vertices, mesh.triangles
    raise ValueError(
        "add_triangles takes (vertex_positions, triangle_indices) or a mesh with vertices and faces, "
        f"not {type(mesh).__name__}"
    )


class RaycastingScene:
    """Open3D's RaycastingScene on kdrt: every query on numpy arrays, the GIL
    released while kdrt works, results in new arrays.

    Geometry ids count the add_* calls from 0; a hit names its geometry and the
    primitive within it (a triangle's index, a sphere's). The scene is committed
    (its BVH or kd-tree built) on the first query after a change, as Open3D's is.
    """

    INVALID_ID = INVALID_ID

    def __init__(self, nthreads: int = 0, device: str = "cpu", accel: str = "bvh") -> None:
        """`device` by kdrt's name; `accel` the structure: "bvh" (faster on
        meshes) or "kd" (kdrt's kd-tree)."""
        self._scene = _kdrt.RaycastingScene(int(nthreads), str(device), str(accel))

    @property
    def device(self) -> str:
        """The device the scene runs on, by kdrt's name ("cpu", "opencl:0", ...)."""
        return self._scene.device

    @property
    def accel(self) -> str:
        """The acceleration structure: "bvh" or "kd"."""
        return self._scene.accel

    def add_triangles(self, vertex_positions: Any, triangle_indices: Any = None) -> int:
        """Adds a triangle mesh: (N, 3) float32 positions and (M, 3) uint32 indices,
        or a mesh object (trimesh, Open3D). Returns its geometry id."""
        if triangle_indices is None:
            vertex_positions, triangle_indices = _mesh_arrays(vertex_positions)
            vertex_positions = np.asarray(
                vertex_positions.numpy() if hasattr(vertex_positions, "numpy") else vertex_positions,
                dtype=np.float32,
            )
        vertices = _as_array(vertex_positions, np.float32, 3, "vertex_positions")
        if vertices.ndim != 2:
            raise ValueError(f"vertex_positions must have shape (N, 3), got {vertices.shape}")
        return self._scene.add_triangles(vertices, _triangle_indices(triangle_indices))

    def add_spheres(self, centers: Any, radii: Any) -> int:
        """Adds spheres as one geometry: (N, 3) float32 centres, (N,) float32 radii.
        Returns its geometry id; a hit's primitive id is the sphere's index."""
        c = _as_array(centers, np.float32, 3, "centers")
        r = np.ascontiguousarray(np.asarray(radii, dtype=np.float32).reshape(-1))
        return self._scene.add_spheres(c, r)

    def cast_rays(self, rays: Any, nthreads: int = 0) -> Dict[str, np.ndarray]:
        """Closest hit of each ray (..., 6) [ox, oy, oz, dx, dy, dz]: t_hit (in units
        of the direction, inf on a miss), geometry_ids, primitive_ids (INVALID_ID on a
        miss), primitive_uvs (..., 2), primitive_normals (..., 3)."""
        return self._scene.cast_rays(_as_array(rays, np.float32, 6, "rays"), int(nthreads))

    def test_occlusions(
        self, rays: Any, tnear: float = 0.0, tfar: float = float("inf"), nthreads: int = 0
    ) -> np.ndarray:
        """Whether each ray hits anything on (tnear, tfar]: bool (...)."""
        return self._scene.test_occlusions(_as_array(rays, np.float32, 6, "rays"), float(tnear), float(tfar), int(nthreads))

    def count_intersections(self, rays: Any, nthreads: int = 0) -> np.ndarray:
        """Hits along each ray: int32 (...). Each triangle once; a sphere once per crossing."""
        return self._scene.count_intersections(_as_array(rays, np.float32, 6, "rays"), int(nthreads))

    def list_intersections(self, rays: Any, nthreads: int = 0) -> Dict[str, np.ndarray]:
        """Every hit of every ray, nearest first per ray: ray_splits (R + 1), ray_ids,
        geometry_ids, primitive_ids, primitive_uvs (H, 2), t_hit. Ray i's hits are
        [ray_splits[i], ray_splits[i + 1])."""
        rays = _as_array(rays, np.float32, 6, "rays")
        return self._scene.list_intersections(rays.reshape(-1, 6), int(nthreads))

    def compute_closest_points(self, query_points: Any, nthreads: int = 0) -> Dict[str, np.ndarray]:
        """The nearest surface point to each point (..., 3): points, geometry_ids,
        primitive_ids, primitive_uvs, primitive_normals."""
        return self._scene.compute_closest_points(_as_array(query_points, np.float32, 3, "query_points"), int(nthreads))

    def compute_distance(self, query_points: Any, nthreads: int = 0) -> np.ndarray:
        """Distance from each point (..., 3) to the surface: float32 (...)."""
        return self._scene.compute_distance(_as_array(query_points, np.float32, 3, "query_points"), int(nthreads))

    def compute_occupancy(self, query_points: Any, nthreads: int = 0, nsamples: int = 1) -> np.ndarray:
        """1.0 inside, 0.0 outside, float32 (...): by the parity of a ray's hits from
        each point, the majority of `nsamples` (odd) rays. Meshes must be watertight."""
        points = _as_array(query_points, np.float32, 3, "query_points")
        inside = self._inside(points, int(nthreads), int(nsamples))
        return inside.astype(np.float32)

    def compute_signed_distance(self, query_points: Any, nthreads: int = 0, nsamples: int = 1) -> np.ndarray:
        """compute_distance, negative inside (compute_occupancy's rule)."""
        points = _as_array(query_points, np.float32, 3, "query_points")
        distance = self._scene.compute_distance(points, int(nthreads))
        inside = self._inside(points, int(nthreads), int(nsamples))
        return np.where(inside, -distance, distance).astype(np.float32)

    def _inside(self, points: np.ndarray, nthreads: int, nsamples: int) -> np.ndarray:
        if nsamples < 1 or nsamples % 2 == 0:
            raise ValueError(f"nsamples must be a positive odd number, got {nsamples}")
        directions = _occupancy_directions(nsamples)
        flat = points.reshape(-1, 3)
        rays = np.empty((nsamples, flat.shape[0], 6), np.float32)
        rays[:, :, :3] = flat
        rays[:, :, 3:] = directions[:, None, :]
        counts = self._scene.count_intersections(rays, nthreads)
        votes = (counts % 2).sum(axis=0)
        return (votes > nsamples // 2).reshape(points.shape[:-1])

    @staticmethod
    def create_rays_pinhole(*args: Any, **kwargs: Any) -> np.ndarray:
        """Open3D's two forms: (fov_deg, center, eye, up, width_px, height_px) with the
        horizontal field of view, or (intrinsic_matrix, extrinsic_matrix, width_px,
        height_px). Returns float32 (height_px, width_px, 6); a ray's direction has a
        camera-space depth of 1, so t_hit is the depth."""
        return _create_rays_pinhole(*args, **kwargs)


def _occupancy_directions(nsamples: int) -> np.ndarray:
    """The rays' directions: one fixed, skew direction, or `nsamples` seeded random unit vectors."""
    if nsamples == 1:
        return np.array([[0.5773503, 0.5773502, 0.5773504]], np.float32)
    rng = np.random.default_rng(0x6B647274)
    d = rng.normal(size=(nsamples, 3))
    return (d / np.linalg.norm(d, axis=1, keepdims=True)).astype(np.float32)


def _create_rays_pinhole(*args: Any, **kwargs: Any) -> np.ndarray:
    names_fov = ["fov_deg", "center", "eye", "up", "width_px", "height_px"]
    names_k = ["intrinsic_matrix", "extrinsic_matrix", "width_px", "height_px"]
    if "fov_deg" in kwargs or (args and np.ndim(_np(args[0])) == 0):
        p = dict(zip(names_fov, args), **kwargs)
        width, height = int(p["width_px"]), int(p["height_px"])
        eye = _np(p["eye"]).astype(np.float64).reshape(3)
        center = _np(p["center"]).astype(np.float64).reshape(3)
        up = _np(p["up"]).astype(np.float64).reshape(3)
        f = center - eye
        if not np.linalg.norm(f) > 0:
            raise ValueError("create_rays_pinhole: eye and center must differ")
        f /= np.linalg.norm(f)
        x = np.cross(up, f)
        if not np.linalg.norm(x) > 0:
            raise ValueError("create_rays_pinhole: up must not be parallel to center - eye")
        x /= np.linalg.norm(x)
        y = np.cross(f, x)
        focal = 0.5 * width / np.tan(np.radians(float(p["fov_deg"])) / 2)
        K = np.array([[focal, 0, 0.5 * width], [0, focal, 0.5 * height], [0, 0, 1]])
        R = np.stack([x, y, f])
        t = -R @ eye
    else:
        p = dict(zip(names_k, args), **kwargs)
        width, height = int(p["width_px"]), int(p["height_px"])
        K = _np(p["intrinsic_matrix"]).astype(np.float64).reshape(3, 3)
        E = _np(p["extrinsic_matrix"]).astype(np.float64).reshape(4, 4)
        R, t = E[:3, :3], E[:3, 3]
    if width < 1 or height < 1:
        raise ValueError(f"create_rays_pinhole: width_px and height_px must be >= 1, got {width}x{height}")
    u, v = np.meshgrid(np.arange(width) + 0.5, np.arange(height) + 0.5)
    pixels = np.stack([u, v, np.ones_like(u)], axis=-1)
    camera = pixels @ np.linalg.inv(K).T
    rays = np.empty((height, width, 6), np.float32)
    rays[..., :3] = -R.T @ t
    rays[..., 3:] = camera @ R
    return rays


def _np(value: Any) -> np.ndarray:
    return np.asarray(value.numpy() if hasattr(value, "numpy") and not isinstance(value, np.ndarray) else value)


@dataclass
class Frame:
    """A rendered frame: image (H, W, 3) float32 linear RGB, ids (H, W) int32 (the
    object each pixel's camera ray hit, -1 for none), t_hit (H, W) float32 and stats."""

    image: np.ndarray
    ids: np.ndarray
    t_hit: np.ndarray
    stats: Dict[str, Any]


def render(
    scene: Any,
    device: str = "cpu",
    width: int = 0,
    height: int = 0,
    samples: int = 0,
    max_depth: int = 0,
    threads: int = 0,
) -> Frame:
    """Renders a kdrt.Scene (or the path of a scene or model file) on `device`.
    0 keeps the scene's size, samples and depth. Ctrl-C cancels (KeyboardInterrupt)."""
    if not isinstance(scene, Scene):
        scene = load_scene(str(scene))
    return Frame(**_kdrt._render(scene, device, width, height, samples, max_depth, threads))
