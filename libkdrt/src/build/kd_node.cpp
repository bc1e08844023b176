// KdNode factories (the bit packing of shared/kdrt_shared.h behind names), tree
// equality, builder names and the build configuration's validation.
#include <kdrt/error.h>
#include <kdrt/kd_tree.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <sstream>

namespace kdrt {

float kd_split(const KdNode& n) { return std::bit_cast<float>(n.word0); }

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

KdNode kd_make_leaf(std::uint32_t leaf_index, std::uint32_t count) {
    if (count > KDRT_MAX_NODE_INDEX)
        throw Error(ErrorCode::Unsupported, "kd-tree leaf too large: " + std::to_string(count) +
                                                " objects do not fit the 30-bit count field");
    return {leaf_index, (count << 2) | KDRT_LEAF_FLAG};
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
    return same_bytes(nodes, o.nodes) && same_bytes(leaves, o.leaves) && leaf_objects == o.leaf_objects &&
           same_bytes(ropes, o.ropes) && bounds == o.bounds && object_count == o.object_count &&
           max_depth == o.max_depth;
}

const char* to_string(KdBuilderKind kind) {
    switch (kind) {
        case KdBuilderKind::Median: return "median";
        case KdBuilderKind::Sah: return "sah";
    }
    return "unknown";
}

KdBuilderKind kd_builder_from_string(const std::string& name) {
    if (name == "median") return KdBuilderKind::Median;
    if (name == "sah") return KdBuilderKind::Sah;
    throw Error(ErrorCode::InvalidArgument, "unknown kd-tree builder '" + name + "' (expected 'median' or 'sah')");
}

namespace {

[[noreturn]] void bad_field(const char* field, const char* rule, double got) {
    std::ostringstream s;
    s << "kd-tree " << field << ": " << rule << ", got " << got;
    throw Error(ErrorCode::InvalidArgument, s.str());
}

}  // namespace

void KdBuildConfig::validate() const {
    if (builder != KdBuilderKind::Median && builder != KdBuilderKind::Sah)
        bad_field("builder", "must be median or sah", static_cast<double>(builder));
    // 64 bounds the fixed-size traversal stacks on both the CPU and the device.
    if (max_depth < 0 || max_depth > KDRT_MAX_TREE_DEPTH) bad_field("max_depth", "must be in [0, 64]", max_depth);
    if (!std::isfinite(traversal_cost) || traversal_cost < 0.0)
        bad_field("traversal_cost", "must be finite and >= 0", traversal_cost);
    if (!std::isfinite(intersection_cost) || intersection_cost <= 0.0)
        bad_field("intersection_cost", "must be finite and > 0", intersection_cost);
    if (!(empty_bonus >= 0.0 && empty_bonus < 1.0)) bad_field("empty_bonus", "must be in [0, 1)", empty_bonus);
    if (!std::isfinite(median_max_duplication) || median_max_duplication < 1.0)
        bad_field("median_max_duplication", "must be finite and >= 1", median_max_duplication);
}

}  // namespace kdrt
