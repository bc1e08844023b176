// The BVH nodes' factories, equality, and the build configuration's validation.
#include "bvh/bvh.h"
#include "bvh/bvh_build.h"

#include <kdrt/error.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>
#include <string>

namespace kdrt {

namespace {

// The nodes have no padding (sizes are static_asserted), so bytewise equality
// is exact equality, float bits of the boxes included.
template <class T>
bool same_bytes(const std::vector<T>& a, const std::vector<T>& b) {
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

[[noreturn]] void bad_field(const char* field, const char* rule, double got) {
    std::ostringstream s;
    s << "BVH build config " << field << ": " << rule << ", got " << got;
    throw Error(ErrorCode::InvalidArgument, s.str());
}

}  // namespace

bool Bvh2::operator==(const Bvh2& o) const {
    return same_bytes(nodes, o.nodes) && leaf_objects == o.leaf_objects && object_count == o.object_count;
}

template <int N>
void WideBvhNodeN<N>::set_empty(int slot) {
    for (int a = 0; a < 3; ++a) {
        box[0][a][slot] = std::numeric_limits<float>::infinity();
        box[1][a][slot] = -std::numeric_limits<float>::infinity();
    }
    child[slot] = 0;
    count[slot] = kBvhLeafFlag;
}

template <int N>
void WideBvhNodeN<N>::set_leaf(int slot, std::uint32_t first, std::uint32_t n) {
    if (n == 0 || n > kBvhMaxLeafCount)
        throw Error(ErrorCode::Unsupported, "BVH leaf of " + std::to_string(n) + " objects: a leaf holds 1 to " +
                                                std::to_string(kBvhMaxLeafCount));
    child[slot] = first;
    count[slot] = kBvhLeafFlag | n;
}

template <int N>
WideBvhNodeN<N> WideBvhNodeN<N>::empty_node() {
    WideBvhNodeN node;
    for (int i = 0; i < N; ++i) node.set_empty(i);
    return node;
}

template <int N>
bool WideBvhN<N>::operator==(const WideBvhN& o) const {
    return same_bytes(nodes, o.nodes) && leaf_objects == o.leaf_objects && bounds == o.bounds &&
           object_count == o.object_count &&
           std::memcmp(&build_sah_cost, &o.build_sah_cost, sizeof build_sah_cost) == 0;
}

template struct WideBvhNodeN<4>;
template struct WideBvhNodeN<8>;
template struct WideBvhN<4>;
template struct WideBvhN<8>;

void BvhBuildConfig::validate() const {
    if (bins < 4 || bins > 256) bad_field("bins", "must be in [4, 256]", bins);
    if (max_leaf_size < 1 || max_leaf_size > 64) bad_field("max_leaf_size", "must be in [1, 64]", max_leaf_size);
    auto cost = [](const char* field, double v) {
        if (!(std::isfinite(v) && v > 0.0 && v <= 1e6)) bad_field(field, "must be finite, > 0 and at most 1e6", v);
    };
    cost("traversal_cost", traversal_cost);
    cost("intersection_cost", intersection_cost);
    cost("sphere_intersection_cost", sphere_intersection_cost);
    if (leaf_block < 1 || leaf_block > 16 || (leaf_block & (leaf_block - 1)) != 0)
        bad_field("leaf_block", "must be 1, 2, 4, 8 or 16", leaf_block);
    if (threads < 0 || threads > 1024) bad_field("threads", "must be in [0, 1024] (0: all cores)", threads);
}

}  // namespace kdrt
