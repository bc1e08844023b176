// Refitting a wide BVH to moved objects: the same topology (every object stays
// in its leaf), every box recomputed bottom up from the objects' new boxes, in
// place. The boxes are exactly what a build would give those leaves (each
// object's box rounded outward to floats, unions above), so a refit BVH is as
// conservative as a built one, Embree's refit quality (rtcCommitScene with
// RTC_BUILD_QUALITY_REFIT). What a refit cannot do is regroup objects that
// moved apart: its SAH cost says how much the hierarchy has degraded.
#pragma once

#include "bvh/bvh.h"

#include <kdrt/aabb.h>

#include <cstdint>
#include <functional>
#include <span>

namespace kdrt {

// When a rebuild is due: once the refit BVH's SAH cost exceeds the built
// one's by this factor. The ratio follows the boxes' areas, which grow when
// objects drift apart within a leaf or a subtree (what a rebuild repairs),
// but also when the objects themselves grow (stretched triangles), which
// slows a rebuilt BVH as much; it so overstates the loss, and the threshold
// is generous. Below it, a refit BVH traces within about a fifth of a
// rebuilt one's time, and a build costs ten refits and more.
inline constexpr double kBvhRebuildSahRatio = 3.0;

struct BvhRefitResult {
    double sah_cost = 0.0;        // bvh_sah_cost after the refit
    double build_sah_cost = 0.0;  // the BVH's build_sah_cost, when it was built
    double ratio() const { return build_sah_cost > 0.0 ? sah_cost / build_sah_cost : 1.0; }
    // The rule: rebuild once the SAH cost has grown by more than kBvhRebuildSahRatio.
    bool rebuild_due() const { return ratio() > kBvhRebuildSahRatio; }
};

// `object_bounds` holds one box per object id (bvh.object_count of them), as
// a build would take them. An object may lose its box (empty: its leaf then
// ignores it), but one that had none when built cannot gain one (it has no
// leaf: rebuild). Throws kdrt::Error(InvalidArgument) for a wrong count, a box
// that is not finite or leaves the float range, or an object without a leaf
// that gained a box; the BVH is then unchanged. `threads` as in BvhBuildConfig;
// the result is the same for any count.
template <int N>
BvhRefitResult refit_bvh(WideBvhN<N>& bvh, std::span<const Aabb> object_bounds, int threads = 0);

// The same with each leaf's box asked for as the pass reaches it, from
// several threads at once: leaf_box(ids) returns the union of objects ids'
// boxes as a build takes them (empty ones left out), or, if any of them is
// one a build refuses, a box that box_use refuses (a NaN, or a bound beyond
// the float range). Asked for one id, it returns that object's box, which
// names the refused object (a union refused though no member alone is blames
// the leaf's first object). Rounding a box outward to floats commutes with the
// union, so the leaf's float box is the one a build gives it, and no array of
// every object's box is made. If leaf_box throws, the BVH is left as it was.
using BvhLeafBox = std::function<Aabb(std::span<const std::uint32_t> ids)>;
template <int N>
BvhRefitResult refit_bvh(WideBvhN<N>& bvh, const BvhLeafBox& leaf_box, int threads = 0);

extern template BvhRefitResult refit_bvh<4>(WideBvhN<4>&, std::span<const Aabb>, int);
extern template BvhRefitResult refit_bvh<8>(WideBvhN<8>&, std::span<const Aabb>, int);
extern template BvhRefitResult refit_bvh<4>(WideBvhN<4>&, const BvhLeafBox&, int);
extern template BvhRefitResult refit_bvh<8>(WideBvhN<8>&, const BvhLeafBox&, int);

}  // namespace kdrt
