#include "raycasting_scene.h"

#include "threads.h"

#include <kdrt/error.h>
#include <kdrt/layout.h>
#include <kdrt/ray_query.h>
#include <kdrt/scene.h>

#include <nanobind/stl/string.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <span>

namespace kdrt::python {

namespace {

constexpr std::uint32_t kInvalidId = 0xFFFFFFFFu;
constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr std::size_t kChunk = 1 << 14;  // rays converted at a time: their records stay in cache

// Rays (..., 6) as QueryRays on (t_min, t_max], [begin, end) of them.
void to_query_rays(const float* rays, std::size_t begin, std::size_t end, float t_min, float t_max,
                   std::vector<QueryRay>& out) {
    out.resize(end - begin);
    for (std::size_t i = begin; i < end; ++i) {
        const float* r = rays + 6 * i;
        out[i - begin] = QueryRay{{r[0], r[1], r[2]}, t_min, {r[3], r[4], r[5]}, t_max};
    }
}

// Runs f(begin, end) over [0, n) in chunks, several at once: each chunk's
// conversions in and out run on the thread that queries it.
template <class F>
void in_chunks(std::size_t n, F&& f) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, (n + kChunk - 1) / kChunk, 1),
                      [&](const tbb::blocked_range<std::size_t>& chunks) {
                          for (std::size_t c = chunks.begin(); c < chunks.end(); ++c)
                              f(c * kChunk, std::min(n, (c + 1) * kChunk));
                      });
}

}  // namespace

Device open_device(const std::string& name) {
    static std::mutex mutex;
    static std::map<std::string, Device> devices;
    std::lock_guard lock(mutex);
    auto it = devices.find(name);
    if (it == devices.end()) it = devices.emplace(name, Device::open(name)).first;
    return it->second;
}

namespace {

Accel accel_by_name(const std::string& name) {
    if (name == "bvh") return Accel::Bvh;
    if (name == "kd") return Accel::KdTree;
    throw nb::value_error(("accel must be \"bvh\" or \"kd\", got \"" + name + "\"").c_str());
}

}  // namespace

RaycastingScene::RaycastingScene(int nthreads, const std::string& device, const std::string& accel)
    : device_(open_device(device.empty() ? "cpu" : device)), accel_(accel_by_name(accel)), nthreads_(nthreads) {
    if (nthreads < 0) throw nb::value_error("nthreads must be >= 0 (0: all cores)");
}

std::uint32_t RaycastingScene::add_triangles(In<float> vertices, In<std::uint32_t> triangles) {
    const auto vshape = shape_of(vertices), tshape = shape_of(triangles);
    if (vshape.size() != 2 || vshape[1] != 3)
        throw nb::value_error(("vertex_positions must have shape (N, 3), got " + shape_text(vshape)).c_str());
    if (tshape.size() != 2 || tshape[1] != 3)
        throw nb::value_error(("triangle_indices must have shape (M, 3), got " + shape_text(tshape)).c_str());
    Geometry g;
    g.vertices.assign(vertices.data(), vertices.data() + vertices.size());
    g.triangles.assign(triangles.data(), triangles.data() + triangles.size());
    for (std::size_t i = 0; i < g.vertices.size(); ++i)
        if (!std::isfinite(g.vertices[i]))
            throw nb::value_error(("vertex_positions[" + std::to_string(i / 3) + "] is not finite").c_str());
    const std::size_t vertex_count = vshape[0];
    for (std::size_t i = 0; i < g.triangles.size(); ++i)
        if (g.triangles[i] >= vertex_count)
            throw nb::value_error(("triangle_indices[" + std::to_string(i / 3) + "] names vertex " +
                                   std::to_string(g.triangles[i]) + " of " + std::to_string(vertex_count))
                                      .c_str());
    std::lock_guard lock(commit_mutex_);
    geometries_.push_back(std::move(g));
    committed_.reset();
    return static_cast<std::uint32_t>(geometries_.size() - 1);
}

std::uint32_t RaycastingScene::add_spheres(In<float> centers, In<float> radii) {
    const auto cshape = shape_of(centers), rshape = shape_of(radii);
    if (cshape.size() != 2 || cshape[1] != 3)
        throw nb::value_error(("centers must have shape (N, 3), got " + shape_text(cshape)).c_str());
    if (rshape.size() != 1 || rshape[0] != cshape[0])
        throw nb::value_error(("radii must have shape (" + std::to_string(cshape[0]) + ",), got " + shape_text(rshape))
                                  .c_str());
    Geometry g;
    g.spheres.resize(4 * cshape[0]);
    for (std::size_t i = 0; i < cshape[0]; ++i) {
        for (int a = 0; a < 3; ++a) g.spheres[4 * i + a] = centers.data()[3 * i + a];
        g.spheres[4 * i + 3] = radii.data()[i];
        for (int a = 0; a < 3; ++a)
            if (!std::isfinite(g.spheres[4 * i + a]))
                throw nb::value_error(("centers[" + std::to_string(i) + "] is not finite").c_str());
        if (!(std::isfinite(radii.data()[i]) && radii.data()[i] > 0.0f))
            throw nb::value_error(("radii[" + std::to_string(i) + "] must be a positive finite number, got " +
                                   std::to_string(radii.data()[i]))
                                      .c_str());
    }
    std::lock_guard lock(commit_mutex_);
    geometries_.push_back(std::move(g));
    committed_.reset();
    return static_cast<std::uint32_t>(geometries_.size() - 1);
}

const CommittedScene& RaycastingScene::committed() {
    std::lock_guard lock(commit_mutex_);
    if (committed_) return *committed_;
    Scene scene;  // no materials: a query-only scene (kdrt/scene.h)
    scene.name = "RaycastingScene";
    for (const Geometry& g : geometries_) {
        if (!g.spheres.empty()) {
            std::vector<Sphere> spheres(g.spheres.size() / 4);
            for (std::size_t i = 0; i < spheres.size(); ++i)
                spheres[i] = {{g.spheres[4 * i], g.spheres[4 * i + 1], g.spheres[4 * i + 2]}, g.spheres[4 * i + 3], 0};
            scene.add_spheres(spheres);
            continue;
        }
        Mesh mesh;
        mesh.positions.resize(g.vertices.size() / 3);
        for (std::size_t i = 0; i < mesh.positions.size(); ++i)
            mesh.positions[i] = {g.vertices[3 * i], g.vertices[3 * i + 1], g.vertices[3 * i + 2]};
        mesh.triangles.resize(g.triangles.size() / 3);
        for (std::size_t i = 0; i < mesh.triangles.size(); ++i)
            mesh.triangles[i].v = {g.triangles[3 * i], g.triangles[3 * i + 1], g.triangles[3 * i + 2]};
        scene.add_mesh(std::move(mesh));
    }
    CommitOptions options;
    options.accel = accel_;
    committed_.emplace(CommittedScene::commit(device_, scene, options));
    return *committed_;
}

template <class Query>
void RaycastingScene::over_ray_chunks(const float* rays, std::size_t n, float t_min, float t_max, int nthreads,
                                      Query&& query) {
    nb::gil_scoped_release nogil;
    const CommittedScene& scene = committed();
    in_arena(threads(nthreads), [&] {
        in_chunks(n, [&](std::size_t begin, std::size_t end) {
            std::vector<QueryRay> q;
            to_query_rays(rays, begin, end, t_min, t_max, q);
            query(scene, begin, end, std::span<const QueryRay>(q));
        });
    });
}

template <class OnPoint>
void RaycastingScene::over_closest_points(const float* points, std::size_t n, int nthreads, OnPoint&& on_point) {
    nb::gil_scoped_release nogil;
    const CommittedScene& scene = committed();
    in_arena(threads(nthreads), [&] {
        const auto* p = reinterpret_cast<const std::array<float, 3>*>(points);
        in_chunks(n, [&](std::size_t begin, std::size_t end) {
            std::vector<ClosestPoint> c(end - begin);
            closest_points(scene, std::span(p + begin, end - begin), c);
            for (std::size_t i = begin; i < end; ++i) on_point(i, c[i - begin]);
        });
    });
}

nb::dict RaycastingScene::cast_rays(In<float> rays, int nthreads) {
    const auto lead = leading_shape(rays, 6, "rays");
    const std::size_t n = count_of(lead);
    auto t_hit = new_array<float>(lead);
    auto geometry_ids = new_array<std::uint32_t>(lead), primitive_ids = new_array<std::uint32_t>(lead);
    auto uvs = new_array<float>(with_last(lead, 2)), normals = new_array<float>(with_last(lead, 3));
    over_ray_chunks(rays.data(), n, 0.0f, kInf, nthreads,
                    [&](const CommittedScene& scene, std::size_t begin, std::size_t end, std::span<const QueryRay> q) {
                        std::vector<QueryHit> h(q.size());
                        intersect(scene, q, h);
                        for (std::size_t i = begin; i < end; ++i) {
                            const QueryHit& hit = h[i - begin];
                            const bool miss = hit.object == KDRT_NO_HIT;
                            t_hit.data()[i] = miss ? kInf : hit.t;
                            geometry_ids.data()[i] = miss ? kInvalidId : hit.geometry;
                            primitive_ids.data()[i] = miss ? kInvalidId : hit.primitive;
                            uvs.data()[2 * i] = miss ? 0.0f : hit.u;
                            uvs.data()[2 * i + 1] = miss ? 0.0f : hit.v;
                            for (int a = 0; a < 3; ++a) normals.data()[3 * i + a] = miss ? 0.0f : hit.normal[a];
                        }
                    });
    nb::dict d;
    d["t_hit"] = t_hit;
    d["geometry_ids"] = geometry_ids;
    d["primitive_ids"] = primitive_ids;
    d["primitive_uvs"] = uvs;
    d["primitive_normals"] = normals;
    return d;
}

nb::ndarray<nb::numpy, bool> RaycastingScene::test_occlusions(In<float> rays, float tnear, float tfar, int nthreads) {
    const auto lead = leading_shape(rays, 6, "rays");
    if (std::isnan(tnear) || std::isnan(tfar) || tnear > tfar)
        throw nb::value_error("test_occlusions: tnear and tfar must be numbers with tnear <= tfar");
    const std::size_t n = count_of(lead);
    auto out = new_array<bool>(lead);
    static_assert(sizeof(bool) == sizeof(std::uint8_t));
    over_ray_chunks(rays.data(), n, tnear, tfar, nthreads,
                    [&](const CommittedScene& scene, std::size_t begin, std::size_t end, std::span<const QueryRay> q) {
                        occluded(scene, q, std::span(reinterpret_cast<std::uint8_t*>(out.data()) + begin, end - begin));
                    });
    return out;
}

nb::ndarray<nb::numpy, std::int32_t> RaycastingScene::count_intersections(In<float> rays, int nthreads) {
    const auto lead = leading_shape(rays, 6, "rays");
    const std::size_t n = count_of(lead);
    auto out = new_array<std::int32_t>(lead);
    over_ray_chunks(rays.data(), n, 0.0f, kInf, nthreads,
                    [&](const CommittedScene& scene, std::size_t begin, std::size_t end, std::span<const QueryRay> q) {
                        count_hits(scene, q,
                                   std::span(reinterpret_cast<std::uint32_t*>(out.data()) + begin, end - begin),
                                   CoincidentHits::OncePerGeometry);
                    });
    return out;
}

nb::dict RaycastingScene::list_intersections(In<float> rays, int nthreads) {
    const auto lead = leading_shape(rays, 6, "rays");
    const std::size_t n = count_of(lead);
    RayHitLists lists;
    {
        nb::gil_scoped_release nogil;
        const CommittedScene& scene = committed();
        in_arena(threads(nthreads), [&] {
            std::vector<QueryRay> q;
            to_query_rays(rays.data(), 0, n, 0.0f, kInf, q);
            lists = all_hits(scene, q, CoincidentHits::OncePerGeometry);
        });
    }
    const std::size_t m = lists.hits.size();
    if (m > kInvalidId) throw Error(ErrorCode::ResourceLimit, "list_intersections: more than 2^32 - 1 hits");
    auto splits = new_array<std::uint32_t>({n + 1});
    auto ray_ids = new_array<std::uint32_t>({m}), geometry_ids = new_array<std::uint32_t>({m});
    auto primitive_ids = new_array<std::uint32_t>({m});
    auto uvs = new_array<float>({m, 2});
    auto t_hit = new_array<float>({m});
    {
        nb::gil_scoped_release nogil;
        for (std::size_t i = 0; i <= n; ++i) splits.data()[i] = static_cast<std::uint32_t>(lists.ray_splits[i]);
        for (std::size_t r = 0; r < n; ++r)
            for (std::uint64_t k = lists.ray_splits[r]; k < lists.ray_splits[r + 1]; ++k) {
                const QueryHit& h = lists.hits[k];
                ray_ids.data()[k] = static_cast<std::uint32_t>(r);
                geometry_ids.data()[k] = h.geometry;
                primitive_ids.data()[k] = h.primitive;
                uvs.data()[2 * k] = h.u;
                uvs.data()[2 * k + 1] = h.v;
                t_hit.data()[k] = h.t;
            }
    }
    nb::dict d;
    d["ray_splits"] = splits;
    d["ray_ids"] = ray_ids;
    d["geometry_ids"] = geometry_ids;
    d["primitive_ids"] = primitive_ids;
    d["primitive_uvs"] = uvs;
    d["t_hit"] = t_hit;
    return d;
}

nb::dict RaycastingScene::compute_closest_points(In<float> points, int nthreads) {
    const auto lead = leading_shape(points, 3, "query_points");
    const std::size_t n = count_of(lead);
    auto out_points = new_array<float>(with_last(lead, 3));
    auto geometry_ids = new_array<std::uint32_t>(lead), primitive_ids = new_array<std::uint32_t>(lead);
    auto uvs = new_array<float>(with_last(lead, 2)), normals = new_array<float>(with_last(lead, 3));
    over_closest_points(points.data(), n, nthreads, [&](std::size_t i, const ClosestPoint& cp) {
        for (int a = 0; a < 3; ++a) out_points.data()[3 * i + a] = cp.point[a];
        geometry_ids.data()[i] = cp.geometry;
        primitive_ids.data()[i] = cp.primitive;
        uvs.data()[2 * i] = cp.u;
        uvs.data()[2 * i + 1] = cp.v;
        for (int a = 0; a < 3; ++a) normals.data()[3 * i + a] = cp.normal[a];
    });
    nb::dict d;
    d["points"] = out_points;
    d["geometry_ids"] = geometry_ids;
    d["primitive_ids"] = primitive_ids;
    d["primitive_uvs"] = uvs;
    d["primitive_normals"] = normals;
    return d;
}

nb::ndarray<nb::numpy, float> RaycastingScene::compute_distance(In<float> points, int nthreads) {
    const auto lead = leading_shape(points, 3, "query_points");
    const std::size_t n = count_of(lead);
    auto out = new_array<float>(lead);
    over_closest_points(points.data(), n, nthreads,
                        [&](std::size_t i, const ClosestPoint& cp) { out.data()[i] = cp.distance; });
    return out;
}

double RaycastingScene::cpp_intersect_ms(In<float> rays, int nthreads) {
    const std::size_t n = count_of(leading_shape(rays, 6, "rays"));
    nb::gil_scoped_release nogil;
    const CommittedScene& scene = committed();
    std::vector<QueryRay> q;
    to_query_rays(rays.data(), 0, n, 0.0f, kInf, q);
    std::vector<QueryHit> h(n);
    const auto start = std::chrono::steady_clock::now();
    in_arena(threads(nthreads), [&] { intersect(scene, q, h); });
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

void bind_raycasting_scene(nb::module_& m) {
    using S = RaycastingScene;
    nb::class_<S>(m, "RaycastingScene", "Open3D's RaycastingScene over kdrt (kdrt/__init__.py wraps it).")
        .def(nb::init<int, const std::string&, const std::string&>(), nb::arg("nthreads") = 0,
             nb::arg("device") = "cpu", nb::arg("accel") = "bvh")
        .def("add_triangles", &S::add_triangles, nb::arg("vertex_positions").noconvert(),
             nb::arg("triangle_indices").noconvert())
        .def("add_spheres", &S::add_spheres, nb::arg("centers").noconvert(), nb::arg("radii").noconvert())
        .def("cast_rays", &S::cast_rays, nb::arg("rays").noconvert(), nb::arg("nthreads") = 0)
        .def("test_occlusions", &S::test_occlusions, nb::arg("rays").noconvert(), nb::arg("tnear") = 0.0f,
             nb::arg("tfar") = std::numeric_limits<float>::infinity(), nb::arg("nthreads") = 0)
        .def("count_intersections", &S::count_intersections, nb::arg("rays").noconvert(), nb::arg("nthreads") = 0)
        .def("list_intersections", &S::list_intersections, nb::arg("rays").noconvert(), nb::arg("nthreads") = 0)
        .def("compute_closest_points", &S::compute_closest_points, nb::arg("query_points").noconvert(),
             nb::arg("nthreads") = 0)
        .def("compute_distance", &S::compute_distance, nb::arg("query_points").noconvert(), nb::arg("nthreads") = 0)
        .def("_cpp_intersect_ms", &S::cpp_intersect_ms, nb::arg("rays").noconvert(), nb::arg("nthreads") = 0)
        .def_prop_ro("device", &S::device_name)
        .def_prop_ro("accel", &S::accel_name)
        .def_prop_ro("geometry_count", &S::geometry_count);
}

}  // namespace kdrt::python
