// kdrt.RaycastingScene's C++ side: Open3D's RaycastingScene (0.20) over a
// kdrt::CommittedScene. The geometry each add_* call gave is kept in float,
// as given; the scene is committed on the first query after a change, and
// the kdrt::Scene built for the commit is dropped once it is done.
#pragma once

#include "arrays.h"

#include <kdrt/commit_options.h>
#include <kdrt/committed_scene.h>
#include <kdrt/device.h>

#include <nanobind/nanobind.h>

#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace kdrt::python {

class RaycastingScene {
public:
    // accel: "bvh" (the default: faster on meshes) or "kd".
    RaycastingScene(int nthreads, const std::string& device, const std::string& accel);

    std::uint32_t add_triangles(In<float> vertices, In<std::uint32_t> triangles);
    std::uint32_t add_spheres(In<float> centers, In<float> radii);

    nb::dict cast_rays(In<float> rays, int nthreads);
    nb::ndarray<nb::numpy, bool> test_occlusions(In<float> rays, float tnear, float tfar, int nthreads);
    nb::ndarray<nb::numpy, std::int32_t> count_intersections(In<float> rays, int nthreads);
    nb::dict list_intersections(In<float> rays, int nthreads);
    nb::dict compute_closest_points(In<float> points, int nthreads);
    nb::ndarray<nb::numpy, float> compute_distance(In<float> points, int nthreads);

    // Milliseconds of the bare kdrt::intersect on these rays, made QueryRays
    // beforehand (the C++ call the Python overhead is measured against).
    double cpp_intersect_ms(In<float> rays, int nthreads);

    std::string device_name() const { return device_.info().id; }
    std::string accel_name() const { return accel_ == Accel::Bvh ? "bvh" : "kd"; }
    std::uint32_t geometry_count() const { return static_cast<std::uint32_t>(geometries_.size()); }

private:
    struct Geometry {
        std::vector<float> vertices;          // 3 per vertex
        std::vector<std::uint32_t> triangles; // 3 per triangle
        std::vector<float> spheres;           // centre and radius: 4 per sphere
    };

    // The committed scene, committed now if the geometry changed; called without the GIL.
    const CommittedScene& committed();
    int threads(int nthreads) const { return nthreads > 0 ? nthreads : nthreads_; }
    // query(scene, begin, end, rays) over [0, n) of `rays` (6 floats each) as
    // QueryRays on (t_min, t_max], in chunks run in parallel, without the GIL.
    template <class Query>
    void over_ray_chunks(const float* rays, std::size_t n, float t_min, float t_max, int nthreads, Query&& query);
    // on_point(i, closest point) for each of n points (3 floats each), likewise.
    template <class OnPoint>
    void over_closest_points(const float* points, std::size_t n, int nthreads, OnPoint&& on_point);

    Device device_;
    Accel accel_;
    int nthreads_;
    std::vector<Geometry> geometries_;
    std::mutex commit_mutex_;  // several Python threads may query at once
    std::optional<CommittedScene> committed_;
};

// Registers kdrt.RaycastingScene's C++ class (kdrt._kdrt.RaycastingScene).
void bind_raycasting_scene(nb::module_& m);

// The device `name`, opened once per process (an OpenCL device's context and programs are kept).
Device open_device(const std::string& name);

}  // namespace kdrt::python
