// closest_points on OpenCL: query_closest_points (cl/closest_point.cl) over
// the caller's points and results, in place or staged (run_host).
#include "opencl/cl_error.h"
#include "opencl/cl_query_launch.h"
#include "opencl/cl_ray_query.h"

#include <kdrt/error.h>

#include <string>

namespace kdrt::detail::ocl {

void query_closest_points(const QueryTarget& target, std::span<const std::array<float, 3>> points,
                          std::span<ClosestPoint> out) {
    static_assert(sizeof(std::array<float, 3>) == 3 * sizeof(float), "the kernel reads points as float[3 n]");
    if (out.size() != points.size())
        throw Error(ErrorCode::InvalidArgument, "closest_points: " + std::to_string(points.size()) + " points but " +
                                                    std::to_string(out.size()) + " results");
    guard_cl("OpenCL closest points on " + target.device->device().info.id, [&] {
        HostQuery q;
        q.in = points.data();
        q.in_size = sizeof(std::array<float, 3>);
        q.out = out.data();
        q.out_size = sizeof(ClosestPoint);
        q.count = points.size();
        q.make = [&](const cl::Buffer& in, const cl::Buffer& results) {
            return make_query_kernel(target, "query_closest_points", in, results);
        };
        run_host(target, q);
    });
}

}  // namespace kdrt::detail::ocl
