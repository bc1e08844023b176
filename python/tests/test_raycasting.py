"""kdrt.RaycastingScene: Open3D's interface, shapes and dtypes, with answers
checked against numpy oracles; on the cpu device and PoCL."""

import numpy as np
import pytest

import kdrt
from conftest import all_hits_numpy, box_mesh, distances_numpy, sphere_mesh

INF = np.float32(np.inf)


def random_rays(n, rng, spread=3.0, center=(0.0, 0.0, 0.0)):
    origins = rng.uniform(-spread, spread, (n, 3)) + center
    targets = rng.uniform(-0.8, 0.8, (n, 3)) + center
    return np.concatenate([origins, (targets - origins) * rng.uniform(0.3, 2.0, (n, 1))], axis=1).astype(np.float32)


def test_box_hits_as_open3d_reports_them(device):
    vertices, faces = box_mesh()
    scene = kdrt.RaycastingScene(device=device)
    assert scene.add_triangles(vertices, faces) == 0
    rays = np.array([[0.5, 0.5, 10, 0, 0, -1], [-1, -1, -1, 0, 0, -1], [0.5, 0.5, 0.5, 0, 0, 2]], np.float32)
    ans = scene.cast_rays(rays)
    assert set(ans) == {"t_hit", "geometry_ids", "primitive_ids", "primitive_uvs", "primitive_normals"}
    assert ans["t_hit"].dtype == np.float32 and ans["t_hit"].shape == (3,)
    assert ans["geometry_ids"].dtype == np.uint32 and ans["primitive_ids"].dtype == np.uint32
    assert ans["primitive_uvs"].shape == (3, 2) and ans["primitive_normals"].shape == (3, 3)
    np.testing.assert_allclose(ans["t_hit"], [9.0, np.inf, 0.25], rtol=1e-6)
    assert ans["geometry_ids"].tolist() == [0, kdrt.INVALID_ID, 0]
    assert ans["primitive_ids"][1] == kdrt.RaycastingScene.INVALID_ID == 2**32 - 1
    assert faces[ans["primitive_ids"][0]].tolist() in ([4, 5, 6], [5, 7, 6])  # the z = 1 face
    np.testing.assert_allclose(ans["primitive_normals"][0], [0, 0, 1], atol=1e-6)
    np.testing.assert_array_equal(ans["primitive_normals"][1], [0, 0, 0])
    assert scene.count_intersections(rays).tolist() == [2, 0, 1]
    assert scene.count_intersections(rays).dtype == np.int32
    occluded = scene.test_occlusions(rays)
    assert occluded.dtype == np.bool_ and occluded.tolist() == [True, False, True]
    assert scene.test_occlusions(rays, tnear=0, tfar=8.5).tolist() == [False, False, True]


def test_leading_shape_is_kept(device):
    scene = kdrt.RaycastingScene(device=device)
    scene.add_triangles(*box_mesh())
    rays = kdrt.RaycastingScene.create_rays_pinhole(60, [0.5, 0.5, 0.5], [-1, -1, -1], [0, 0, 1], 8, 6)
    assert rays.shape == (6, 8, 6) and rays.dtype == np.float32
    ans = scene.cast_rays(rays)
    assert ans["t_hit"].shape == (6, 8) and ans["primitive_normals"].shape == (6, 8, 3)
    # The box fills the middle of the picture (Open3D's answer: 12 of 48 rays hit).
    assert np.isfinite(ans["t_hit"]).sum() == 12 and np.isfinite(ans["t_hit"][2:4, 3:5]).all()
    assert scene.count_intersections(rays).shape == (6, 8)
    assert scene.test_occlusions(rays).shape == (6, 8)


def test_pinhole_rays_match_open3d_convention():
    rays = kdrt.RaycastingScene.create_rays_pinhole(
        fov_deg=60, center=[0.5, 0.5, 0.5], eye=[-1, -1, -1], up=[0, 0, 1], width_px=4, height_px=3)
    np.testing.assert_allclose(rays[0, 0], [-1, -1, -1, 1.0013876, 0.38901517, 0.341648], rtol=1e-5)
    np.testing.assert_allclose(rays[2, 3], [-1, -1, -1, 0.15331292, 0.7656853, 0.81305254], rtol=1e-5)
    # The intrinsic/extrinsic form of the same camera gives the same rays.
    f = np.array([1.5, 1.5, 1.5]) / np.linalg.norm([1.5, 1.5, 1.5])
    x = np.cross([0, 0, 1], f)
    x /= np.linalg.norm(x)
    y = np.cross(f, x)
    R = np.stack([x, y, f])
    E = np.eye(4)
    E[:3, :3], E[:3, 3] = R, -R @ np.array([-1, -1, -1])
    focal = 2 / np.tan(np.radians(30))
    K = np.array([[focal, 0, 2], [0, focal, 1.5], [0, 0, 1]])
    np.testing.assert_allclose(kdrt.RaycastingScene.create_rays_pinhole(K, E, 4, 3), rays, rtol=1e-5, atol=1e-6)


def test_counts_and_lists_equal_every_triangle(device, accel):
    rng = np.random.default_rng(1)
    vertices, faces = sphere_mesh(12)
    vertices2, faces2 = box_mesh((-0.5, -0.5, -0.5), (0.5, 0.5, 0.5))
    scene = kdrt.RaycastingScene(device=device, accel=accel)
    assert scene.accel == accel
    scene.add_triangles(vertices, faces)
    scene.add_triangles(vertices2, faces2)
    rays = random_rays(300, rng)
    allv = np.concatenate([vertices, vertices2])
    allf = np.concatenate([faces, faces2 + len(vertices)])
    expected = all_hits_numpy(allv, allf, rays)
    counts = scene.count_intersections(rays)
    assert counts.tolist() == [len(e) for e in expected]
    lists = scene.list_intersections(rays)
    assert lists["ray_splits"].dtype == np.uint32 and lists["ray_splits"].shape == (301,)
    assert lists["ray_splits"][-1] == counts.sum() == len(lists["t_hit"])
    assert lists["primitive_uvs"].shape == (counts.sum(), 2)
    for i, e in enumerate(expected):
        lo, hi = lists["ray_splits"][i], lists["ray_splits"][i + 1]
        assert (lists["ray_ids"][lo:hi] == i).all()
        got = [(int(g), int(p)) for g, p in zip(lists["geometry_ids"][lo:hi], lists["primitive_ids"][lo:hi])]
        want = [(0, k) if k < len(faces) else (1, k - len(faces)) for _, k in e]
        assert got == want
        np.testing.assert_allclose(lists["t_hit"][lo:hi], [t for t, _ in e], rtol=1e-5)


def test_closest_points_distance_and_sign(device):
    vertices, faces = box_mesh()
    scene = kdrt.RaycastingScene(device=device)
    scene.add_triangles(vertices, faces)
    points = np.array([[0.5, 0.5, 2], [0.5, 0.2, 0.5], [2, 2, 2], [0.5, 0.5, -1]], np.float32)
    ans = scene.compute_closest_points(points)
    assert set(ans) == {"points", "geometry_ids", "primitive_ids", "primitive_uvs", "primitive_normals"}
    np.testing.assert_allclose(ans["points"], [[0.5, 0.5, 1], [0.5, 0, 0.5], [1, 1, 1], [0.5, 0.5, 0]], atol=1e-6)
    np.testing.assert_allclose(ans["primitive_normals"][0], [0, 0, 1], atol=1e-6)
    np.testing.assert_allclose(scene.compute_distance(points), [1, 0.2, np.sqrt(3), 1], rtol=1e-6)
    np.testing.assert_allclose(scene.compute_signed_distance(points), [1, -0.2, np.sqrt(3), 1], rtol=1e-6)
    assert scene.compute_occupancy(points).tolist() == [0, 1, 0, 0]
    assert scene.compute_occupancy(points, nsamples=5).tolist() == [0, 1, 0, 0]
    # A grid with no point on the surface (whose inside is undefined).
    grid = np.stack(np.meshgrid(*[np.linspace(-0.45, 1.45, 9)] * 3, indexing="ij"), -1).astype(np.float32)
    occupancy = scene.compute_occupancy(grid)
    inside = np.all((grid > 0) & (grid < 1), axis=-1)
    assert occupancy.shape == (9, 9, 9) and (occupancy == inside).all()


def test_closest_points_equal_every_triangle(device, accel):
    rng = np.random.default_rng(2)
    vertices, faces = sphere_mesh(10, radius=1.5)
    scene = kdrt.RaycastingScene(device=device, accel=accel)
    scene.add_triangles(vertices, faces)
    points = rng.uniform(-3, 3, (500, 3)).astype(np.float32)
    distance = scene.compute_distance(points)
    # The distance to a triangle is at least the distance to its plane, and the
    # closest point found lies on the surface and is that far away.
    ans = scene.compute_closest_points(points)
    np.testing.assert_allclose(np.linalg.norm(ans["points"] - points, axis=1), distance, rtol=1e-5, atol=1e-6)
    tri = vertices[faces[ans["primitive_ids"]]]
    u, v = ans["primitive_uvs"][:, 0:1], ans["primitive_uvs"][:, 1:2]
    np.testing.assert_allclose(tri[:, 0] * (1 - u - v) + tri[:, 1] * u + tri[:, 2] * v, ans["points"], atol=1e-5)
    np.testing.assert_allclose(distance, distances_numpy(vertices, faces, points), rtol=1e-5, atol=1e-6)


def test_spheres_as_one_geometry(device):
    scene = kdrt.RaycastingScene(device=device)
    scene.add_triangles(*box_mesh((10, 10, 10), (11, 11, 11)))
    gid = scene.add_spheres(np.array([[0, 0, 0], [3, 0, 0]], np.float32), np.array([1, 0.5], np.float32))
    assert gid == 1
    rays = np.array([[3, 0, -5, 0, 0, 1], [0, 0, -5, 0, 0, 1]], np.float32)
    ans = scene.cast_rays(rays)
    assert ans["geometry_ids"].tolist() == [1, 1] and ans["primitive_ids"].tolist() == [1, 0]
    np.testing.assert_allclose(ans["t_hit"], [4.5, 4.0], rtol=1e-6)
    assert scene.count_intersections(rays).tolist() == [2, 2]


def test_mesh_objects_and_open3d_tensors_are_taken():
    class TriMesh:  # what trimesh.Trimesh offers
        def __init__(self, v, f):
            self.vertices, self.faces = v.astype(np.float64), f.astype(np.int64)

    scene = kdrt.RaycastingScene()
    assert scene.add_triangles(TriMesh(*box_mesh())) == 0
    assert scene.cast_rays(np.array([[0.5, 0.5, 5, 0, 0, -1]], np.float32))["t_hit"][0] == 4


def test_commit_again_after_adding():
    scene = kdrt.RaycastingScene()
    scene.add_triangles(*box_mesh())
    ray = np.array([[0.5, 0.5, 10, 0, 0, -1]], np.float32)
    assert scene.cast_rays(ray)["t_hit"][0] == 9
    scene.add_triangles(*box_mesh((0, 0, 5), (1, 1, 6)))
    ans = scene.cast_rays(ray)
    assert ans["t_hit"][0] == 4 and ans["geometry_ids"][0] == 1


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda s: s.cast_rays(np.zeros((4, 6), np.float64)), "rays must be float32"),
        (lambda s: s.cast_rays(np.zeros((4, 5), np.float32)), r"shape \(\.\.\., 6\)"),
        (lambda s: s.compute_distance(np.zeros((4, 2), np.float32)), r"shape \(\.\.\., 3\)"),
        (lambda s: s.add_triangles(np.zeros((3, 3), np.float32), np.array([[0, 1, 3]], np.uint32)), "names vertex 3"),
        (lambda s: s.add_triangles(np.array([[0, 0, np.nan]] * 3, np.float32), np.array([[0, 1, 2]])), "not finite"),
        (lambda s: s.add_triangles(np.zeros((3, 3), np.float32), np.array([[0, 1, -2]])), r"\[0, 2\^32 - 2\]"),
        (lambda s: s.add_triangles(np.zeros((3, 2), np.float32), np.array([[0, 1, 2]])), r"\(\.\.\., 3\)"),
        (lambda s: s.add_spheres(np.zeros((1, 3), np.float32), np.array([-1], np.float32)), "positive"),
        (lambda s: s.compute_occupancy(np.zeros((1, 3), np.float32), nsamples=2), "odd"),
        (lambda s: s.test_occlusions(np.zeros((1, 6), np.float32), tnear=2, tfar=1), "tnear <= tfar"),
    ],
)
def test_bad_input_raises_value_error(call, message):
    scene = kdrt.RaycastingScene()
    scene.add_triangles(*box_mesh())
    with pytest.raises(ValueError, match=message):
        call(scene)


def test_nan_rays_miss_and_unknown_devices_raise():
    scene = kdrt.RaycastingScene()
    scene.add_triangles(*box_mesh())
    rays = np.array([[np.nan, 0.5, 5, 0, 0, -1], [0.5, 0.5, 5, 0, 0, 0]], np.float32)
    ans = scene.cast_rays(rays)
    assert np.isinf(ans["t_hit"]).all() and (ans["geometry_ids"] == kdrt.INVALID_ID).all()
    assert scene.count_intersections(rays).tolist() == [0, 0]
    with pytest.raises(kdrt.Error) as info:
        kdrt.RaycastingScene(device="no-such-device")
    assert info.value.code == "device error"


def test_empty_scene_misses_everything(device):
    scene = kdrt.RaycastingScene(device=device)
    ans = scene.cast_rays(np.array([[0, 0, 0, 1, 0, 0]], np.float32))
    assert np.isinf(ans["t_hit"][0]) and ans["geometry_ids"][0] == kdrt.INVALID_ID


def test_threads_query_one_scene_at_once():
    from concurrent.futures import ThreadPoolExecutor

    scene = kdrt.RaycastingScene()
    scene.add_triangles(*sphere_mesh(16))
    rays = random_rays(2000, np.random.default_rng(3))
    alone = scene.cast_rays(rays)["t_hit"]
    with ThreadPoolExecutor(4) as pool:
        results = list(pool.map(lambda _: scene.cast_rays(rays, nthreads=1)["t_hit"], range(8)))
    for r in results:
        np.testing.assert_array_equal(r, alone)
