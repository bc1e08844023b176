// Bounding volume hierarchies as plain data, beside the kd-tree: the binary
// BVH that the builder makes (Bvh2) and the wide BVH that the cpu device
// traverses (WideBvhN, N children per node, collapsed from a Bvh2).
//
// Both reference every object exactly once (no spatial splits): a leaf is a
// contiguous range of `leaf_objects`, object ids numbered as everywhere in
// kdrt (spheres first, then triangles), so the leaf tests that take
// (const uint32_t* ids, uint32_t count) run on BVH leaves unchanged. Boxes are
// floats, each the double box it stands for rounded outward, so a box never
// misses a point of its objects. Builders: bvh_build.h; traversals:
// cpu/traverse_bvh.h; checks, statistics, refit and files: the other bvh/ headers.
#pragma once

#include <kdrt/aabb.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace kdrt {

// The deepest BVH (binary or wide; the root is at depth 0) the builder makes
// and the loaders accept: it bounds the traversals' stacks.
inline constexpr int kBvhMaxDepth = 63;

// ---- Binary BVH -------------------------------------------------------------
// 32 bytes. The two children of an inner node are adjacent (first, first + 1).
struct Bvh2Node {
    float lo[3], hi[3];   // the node's box
    std::uint32_t first;  // inner: index of its first child; leaf: first index into leaf_objects
    std::uint32_t count;  // 0: inner node; else the leaf's object count
};
static_assert(sizeof(Bvh2Node) == 32);

inline bool bvh2_is_leaf(const Bvh2Node& n) { return n.count != 0; }

struct Bvh2 {
    std::vector<Bvh2Node> nodes;              // root at 0; none for a BVH over no objects
    std::vector<std::uint32_t> leaf_objects;  // each leaf's ids a range, ascending within the leaf
    std::uint32_t object_count = 0;           // objects it was built over (ids are below)

    bool operator==(const Bvh2&) const;  // bit for bit, boxes included
};

// ---- Wide BVH -----------------------------------------------------------------
// A node holds N child slots, each a box and a reference, by component (SoA),
// so that one vector step tests all N boxes against a ray. A slot is
//  - an inner child:  count[i] == 0, child[i] = its node index (always greater
//                     than the parent's: nodes come after their parents);
//  - a leaf:          count[i] == kBvhLeafFlag | k (k >= 1), its objects
//                     leaf_objects[child[i] .. child[i] + k);
//  - empty:           count[i] == kBvhLeafFlag (a leaf of no objects), child[i]
//                     == 0 and the empty box (lo = +inf, hi = -inf), which no
//                     ray meets. Empty slots come after the used ones.
// box[0] are the lower bounds, box[1] the upper: box[s][axis][slot], so that
// a traversal picks a slab's near and far planes by the ray's direction sign.
// 32 N bytes: 256 for N = 8, four cache lines.
inline constexpr std::uint32_t kBvhLeafFlag = 0x80000000u;
inline constexpr std::uint32_t kBvhMaxLeafCount = 0x7FFFFFFFu;

template <int N>
struct alignas(N >= 8 ? 64 : 32) WideBvhNodeN {
    static_assert(N == 4 || N == 8, "wide BVH nodes hold 4 or 8 children");
    static constexpr int kWidth = N;
    float box[2][3][N];
    std::uint32_t child[N];
    std::uint32_t count[N];

    bool is_leaf(int slot) const { return (count[slot] & kBvhLeafFlag) != 0; }
    std::uint32_t leaf_count(int slot) const { return count[slot] & kBvhMaxLeafCount; }
    bool is_empty(int slot) const { return count[slot] == kBvhLeafFlag; }
    int used_slots() const {
        int k = 0;
        while (k < N && !is_empty(k)) ++k;
        return k;
    }
    Aabb slot_box(int slot) const {
        Aabb b;
        for (int a = 0; a < 3; ++a) {
            b.lo[a] = box[0][a][slot];
            b.hi[a] = box[1][a][slot];
        }
        return b;
    }
    void set_box(int slot, const float (&lo)[3], const float (&hi)[3]) {
        for (int a = 0; a < 3; ++a) {
            box[0][a][slot] = lo[a];
            box[1][a][slot] = hi[a];
        }
    }
    void set_empty(int slot);  // the empty slot described above
    void set_inner(int slot, std::uint32_t node) {
        child[slot] = node;
        count[slot] = 0;
    }
    void set_leaf(int slot, std::uint32_t first, std::uint32_t count);  // throws if count does not fit

    // A node of empty slots.
    static WideBvhNodeN empty_node();
};
static_assert(sizeof(WideBvhNodeN<8>) == 256 && sizeof(WideBvhNodeN<4>) == 128);

template <int N>
struct WideBvhN {
    using Node = WideBvhNodeN<N>;
    static constexpr int kWidth = N;
    std::vector<Node> nodes;                  // root at 0, always there (all empty for no objects)
    std::vector<std::uint32_t> leaf_objects;  // each leaf's ids a range, ascending within the leaf
    Aabb bounds;                              // the union of the root's slots (float values); empty for no objects
    std::uint32_t object_count = 0;           // objects it was built over (ids are below)
    // bvh_sah_cost() when it was built: refit_bvh() compares against it.
    double build_sah_cost = 0.0;

    bool operator==(const WideBvhN&) const;  // bit for bit, boxes included
};

// The width the cpu device traverses, in both of its instruction-set copies:
// with eight children a ray takes fewer node steps, which outweighs the
// baseline copy testing a node's boxes in two 4-lane steps (cpu/traverse_bvh.h).
inline constexpr int kWideBvhWidth = 8;
using WideBvhNode = WideBvhNodeN<kWideBvhWidth>;
using WideBvh = WideBvhN<kWideBvhWidth>;

extern template struct WideBvhNodeN<4>;
extern template struct WideBvhNodeN<8>;
extern template struct WideBvhN<4>;
extern template struct WideBvhN<8>;

}  // namespace kdrt
