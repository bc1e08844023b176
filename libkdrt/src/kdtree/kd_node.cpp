// KdNode factories (the bit packing of kdrt/layout.h behind names), tree
// equality, builder names and the build configuration's validation.
#include <kdrt/error.h>
#include <kdrt/kd_tree.h>

#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <sstream>

namespace kdrt {

KdNode kd_make_inner(int axis, float split, std::uint32_t above_child) {
    if (axis < 0 || axis > 2)
        throw Error(ErrorCode::InvalidArgument, "kd-tree inner node: split axis must be 0, 1 or 2, got " +
                                                    std::to_string(axis));
    if (above_child > KDRT_MAX_NODE_INDEX)
        throw Error(ErrorCode::Unsupported, "kd-tree too large: node index " + std::to_string(above_child) +
                                                " does not fit the 30-bit child field (max " +
                                                std::to_string(KDRT_MAX_NODE_INDEX) + ")");
    return {std::bit_cast<std::uint32_t>(split), (above_child << 2) | static_cast<std::uint32_t>(axis)};
}

KdNode kd_make_leaf(std::uint32_t first, std::uint32_t count) {
    if (count > KDRT_MAX_NODE_INDEX)
        throw Error(ErrorCode::Unsupported, "kd-tree leaf too large: " + std::to_string(count) +
                                                " objects do not fit the 30-bit count field");
    return {first, (count << 2) | KDRT_LEAF_FLAG};
}

namespace {

// The shared structs have no padding (sizes are static_asserted), so bytewise
// equality is exact equality, including the float bits of splits and boxes.
template <class T>
bool same_bytes(const std::vector<T>& a, const std::vector<T>& b) {
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

}  // namespace

bool KdTree::operator==(const KdTree& o) const {
    return same_bytes(nodes, o.nodes) && leaf_objects == o.leaf_objects &&
           same_bytes(ropes, o.ropes) && bounds == o.bounds && object_count == o.object_count &&
           max_depth == o.max_depth;
}

namespace {

[[noreturn]] void bad_field(const char* field, const char* rule, double got) {
    std::ostringstream s;
    s << "kd-tree " << field << ": " << rule << ", got " << got;
    throw Error(ErrorCode::InvalidArgument, s.str());
}

}  // namespace

KdBuildConfig KdBuildConfig::with_triangle_cost(double triangle_cost) const {
    KdBuildConfig c = *this;
    if (c.intersection_cost == 0.0) c.intersection_cost = triangle_cost;
    return c;
}

void KdBuildConfig::validate() const {
    if (builder != KdBuilderKind::Median && builder != KdBuilderKind::Sah && builder != KdBuilderKind::SahExact)
        bad_field("builder", "must be median, sah or sah-exact", static_cast<double>(builder));
    // 64 bounds the fixed-size traversal stacks on both the CPU and the device.
    if (max_depth < 0 || max_depth > KDRT_MAX_TREE_DEPTH) bad_field("max_depth", "must be in [0, 64]", max_depth);
    if (!std::isfinite(traversal_cost) || traversal_cost < 0.0)
        bad_field("traversal_cost", "must be finite and >= 0", traversal_cost);
    if (!std::isfinite(intersection_cost) || intersection_cost < 0.0)
        bad_field("intersection_cost", "must be finite and >= 0 (0: the device's own)", intersection_cost);
    if (!(empty_bonus >= 0.0 && empty_bonus < 1.0)) bad_field("empty_bonus", "must be in [0, 1)", empty_bonus);
    if (!std::isfinite(median_max_duplication) || median_max_duplication < 1.0)
        bad_field("median_max_duplication", "must be finite and >= 1", median_max_duplication);
    if (!std::isfinite(sphere_intersection_cost) || sphere_intersection_cost <= 0.0)
        bad_field("sphere_intersection_cost", "must be finite and > 0", sphere_intersection_cost);
    // Bounded so that the fixed-point cost sums of a build cannot overflow.
    if (intersection_cost > 1e6) bad_field("intersection_cost", "must be at most 1e6", intersection_cost);
    if (sphere_intersection_cost > 1e6)
        bad_field("sphere_intersection_cost", "must be at most 1e6", sphere_intersection_cost);
    if (sah_bins < 2 || sah_bins > 1024) bad_field("sah_bins", "must be in [2, 1024]", sah_bins);
    if (threads < 0 || threads > 1024) bad_field("threads", "must be in [0, 1024] (0: all cores)", threads);
    if (!(duplication_limit >= 1.0 && duplication_limit <= 1e6))
        bad_field("duplication_limit", "must be in [1, 1e6]", duplication_limit);
    if (memory_budget != 0 && memory_budget < (std::size_t{1} << 20))
        bad_field("memory_budget", "must be 0 (automatic) or at least 1 MiB", static_cast<double>(memory_budget));
}

std::size_t KdBuildConfig::effective_memory_budget() const {
    if (memory_budget != 0) return memory_budget;
    // Half the physical memory, at most 16 GiB: a build never takes the machine down.
    const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
    const std::size_t physical =
        pages > 0 && page > 0 ? static_cast<std::size_t>(pages) * static_cast<std::size_t>(page) : std::size_t{8} << 30;
    return std::min(physical / 2, std::size_t{16} << 30);
}

}  // namespace kdrt
