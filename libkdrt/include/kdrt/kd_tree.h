// The kd-tree as plain data, in the flat layout that CPU traversals and OpenCL
// buffers share (the layout is documented in kdrt/layout.h), plus the
// builders' front door and the tree statistics.
#pragma once

#include <kdrt/export.h>
#include <kdrt/aabb.h>
#include <kdrt/layout.h>

#include <bit>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace kdrt {

// Named accessors hiding KdNode's bit packing.
inline bool kd_is_leaf(const KdNode& n) { return (n.word1 & 3u) == KDRT_LEAF_FLAG; }
inline int kd_axis(const KdNode& n) { return static_cast<int>(n.word1 & 3u); }
inline std::uint32_t kd_above_child(const KdNode& n) { return n.word1 >> 2; }
inline std::uint32_t kd_leaf_first(const KdNode& n) { return n.word0; }  // into leaf_objects
inline std::uint32_t kd_leaf_count(const KdNode& n) { return n.word1 >> 2; }
inline float kd_split(const KdNode& n) { return std::bit_cast<float>(n.word0); }  // inline: every node step reads it
KDRT_API KdNode kd_make_inner(int axis, float split, std::uint32_t above_child);  // throws if it does not fit
KDRT_API KdNode kd_make_leaf(std::uint32_t first, std::uint32_t count);  // throws if count does not fit

struct KDRT_API KdTree {
    std::vector<KdNode> nodes;                // depth-first, root at 0
    std::vector<std::uint32_t> leaf_objects;  // object ids referenced by the leaves, each leaf's a range
    std::vector<KdLeafRopes> ropes;           // one per node (a leaf's at its node id, inner nodes' unused);
                                              // empty until build_ropes() (renders build them only for the
                                              // ropes traversal)
    Aabb bounds;                              // root cell; float-representable values
    std::uint32_t object_count = 0;           // objects the tree was built over
    int max_depth = 0;                        // the depth limit it was built with

    bool operator==(const KdTree&) const;
    bool has_ropes() const { return !ropes.empty() && ropes.size() == nodes.size(); }
    std::size_t leaf_count() const { return (nodes.size() + 1) / 2; }  // every inner node has two children
};

// What a builder sees of the scene: one box per object and a way to clip an
// object to a cell (for "perfect splits"). Builders never see triangles.
struct KdBuildInput {
    std::vector<Aabb> bounds;  // conservative bounds of each object id
    // Conservative bounds of the part of object `id` inside `cell` (empty if none).
    // May be null: then bounds[id] ∩ cell is used.
    std::function<Aabb(std::uint32_t id, const Aabb& cell)> clip;
    // Objects [0, sphere_count) are spheres, the rest triangles: the SAH
    // builders cost their intersection tests apart (KdBuildConfig).
    std::uint32_t sphere_count = 0;
    // Optional, for speed: both of clip's answers for the two halves of `cell`
    // cut at `pos` on `axis` (below: hi[axis] = pos, above: lo[axis] = pos),
    // in one call that shares their work. May be null: then clip is called twice.
    std::function<void(std::uint32_t id, const Aabb& cell, int axis, double pos, Aabb& below, Aabb& above)>
        split = nullptr;
};

// Median: the study's spatial median. Sah: binned SAH on large nodes, the
// exact sweep below exact_threshold objects, parallel (the default).
// SahExact: the exact O(N log N) sweep everywhere, serial.
enum class KdBuilderKind { Median, Sah, SahExact };

KDRT_API const char* to_string(KdBuilderKind kind);
KDRT_API KdBuilderKind kd_builder_from_string(const std::string& name);  // "median" | "sah" | "sah-exact"; throws

struct KDRT_API KdBuildConfig {
    KdBuilderKind builder = KdBuilderKind::Sah;
    int max_depth = 0;               // 0: automatic (study: 10 for median; SAH: 8 + 1.3 log2 N)
    // SAH cost constants in one unit: an inner-node step here, the object tests
    // below (under their raw cost: the SAH assumes rays never stop at a hit).
    double traversal_cost = 1.0;
    // One triangle (or unclassified object) test. 0, the default: the cost of
    // the device whose commit or render builds the tree (Device::triangle_cost()),
    // and kGenericTriangleCost where no device is known (build_kd_tree,
    // build_scene_tree, kd_tree_stats).
    double intersection_cost = 0.0;
    static constexpr double kGenericTriangleCost = 0.6;
    double sphere_intersection_cost = 0.6;  // one sphere test (objects below KdBuildInput::sphere_count)
    double empty_bonus = 0.2;        // SAH: cost reduction for splits that cut off empty space, [0, 1)
    double median_max_duplication = 1.8;  // median: abandon an axis when both sides hold more than this x objects

    // Binned SAH: the most bins per axis (a node of n objects uses n, at
    // least 8), and the node size below which the exact sweep takes over.
    int sah_bins = 64;
    std::size_t exact_threshold = 8;
    int threads = 0;  // build threads (Sah builder), 0 = all; the tree is the same for any count

    // Bounded cost. duplication_limit bounds the leaf references to that many
    // times the objects (nodes past their share become leaves: the tree stays
    // correct, only slower to trace); memory_budget bounds the bytes the build
    // may hold (0: half the machine's physical memory, at most 16 GiB).
    // Exceeding the budget throws kdrt::Error(ResourceLimit).
    double duplication_limit = 16.0;
    std::size_t memory_budget = 0;

    // Called during long builds with the fraction done, from one builder
    // thread at a time; returning false cancels the build, which then throws
    // kdrt::Error(Cancelled).
    std::function<bool(double)> progress;

    void validate() const;  // throws kdrt::Error(InvalidArgument) naming the bad field
    // This config with an intersection_cost of 0 replaced by `triangle_cost`.
    KdBuildConfig with_triangle_cost(double triangle_cost) const;
    std::size_t effective_memory_budget() const;  // memory_budget, or the machine's default
};

// Builds the tree (nodes, leaf lists; no ropes).
KDRT_API KdTree build_kd_tree(const KdBuildInput& input, const KdBuildConfig& config);

// Adds the six ropes per leaf and the leaf boxes (Popov et al. 2007, with the
// rope optimisation that pushes each rope down to the deepest node covering the face).
KDRT_API void build_ropes(KdTree& tree);

struct KdTreeStats {
    std::size_t nodes = 0, inner_nodes = 0, leaves = 0, empty_leaves = 0;
    int max_leaf_depth = 0;
    double mean_leaf_depth = 0.0;
    double mean_objects_per_leaf = 0.0;      // over non-empty leaves
    double duplication = 0.0;                // references / objects
    double sah_cost = 0.0;                   // expected cost with the config's constants
    std::size_t node_bytes = 0, leaf_object_bytes = 0, rope_bytes = 0;  // nodes, leaf lists, ropes
    std::size_t objects = 0;                 // the tree's object count, the "per object" denominator
    std::size_t total_bytes() const { return node_bytes + leaf_object_bytes + rope_bytes; }
    // Bytes per object (per triangle in a mesh scene); 0 for a tree over no objects.
    double per_object(std::size_t bytes) const {
        return objects ? static_cast<double>(bytes) / static_cast<double>(objects) : 0.0;
    }
};

KDRT_API KdTreeStats kd_tree_stats(const KdTree& tree, const KdBuildConfig& config = {});

// Checks the structural invariants (every child, leaf, object and rope index in
// range, depth-first order so no cycles, boxes sane). Throws
// kdrt::Error(CorruptTree) naming the first violation.
KDRT_API void check_kd_tree(const KdTree& tree);

// Checks that the tree holds every object it should: each object whose bounds
// (object_bounds[id], as given to the builder) are non-empty and overlap the
// tree's box is referenced by some leaf. A structurally sound tree that drops
// objects would render them invisible. O(objects + references). Throws
// kdrt::Error(CorruptTree) naming the first missing object.
KDRT_API void check_kd_tree_covers(const KdTree& tree, const std::vector<Aabb>& object_bounds);

}  // namespace kdrt
