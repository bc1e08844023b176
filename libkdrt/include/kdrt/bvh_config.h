// The bounding volume hierarchy a scene can be committed with
// (CommitOptions::accel = Accel::Bvh): its builder's settings and its
// statistics. The hierarchy itself is internal: binned SAH (Wald 2007) over
// the objects' boxes, collapsed to eight children per node for the cpu
// device's vector box tests and the kernels; every object in exactly one leaf.
#pragma once

#include <kdrt/export.h>

#include <cstddef>
#include <functional>

namespace kdrt {

struct KDRT_API BvhBuildConfig {
    // Binned SAH (Wald 2007): centroid bins per axis for a node's split, [4, 256].
    // A node of n objects bins into min(bins, max(n, 8)).
    int bins = 32;
    // The most objects in a leaf, [1, 64]; a node of at most this many becomes
    // a leaf when the SAH finds no cheaper split.
    int max_leaf_size = 8;
    // SAH cost constants, in units of one box test of a binary node (> 0,
    // at most 1e6). A node's split costs traversal_cost plus its children's
    // object costs weighted by their area; a leaf costs its objects'.
    // Leaves are tested leaf_block triangles at a time: a leaf of n triangles
    // costs ceil(n / leaf_block) triangle tests; 1, 2, 4, 8 or 16. 8 is the
    // AVX2 cpu device's block in float (in double, the SSE copy and the CPU
    // kernels test blocks of 4, a full leaf in two).
    double traversal_cost = 1.0;
    double intersection_cost = 1.0;         // one triangle test (one block of leaf_block)
    double sphere_intersection_cost = 1.0;  // one sphere test
    int leaf_block = 8;
    int threads = 0;  // build threads, [0, 1024], 0 = all; the BVH is the same for any count
    // Called now and then with the fraction done, from one builder thread at a
    // time; returning false cancels the build, which then throws kdrt::Error(Cancelled).
    std::function<bool(double)> progress;

    void validate() const;  // throws kdrt::Error(InvalidArgument) naming the bad field
};

struct BvhStats {
    std::size_t nodes = 0;        // wide nodes
    std::size_t leaves = 0;       // leaf slots
    std::size_t empty_slots = 0;  // slots holding nothing
    int depth = 0;                // wide levels from the root to the deepest leaf (a root alone: 1)
    double mean_leaf_size = 0.0;  // objects per leaf
    double sah_cost = 0.0;        // bvh_sah_cost
    double build_sah_cost = 0.0;  // the BVH's build_sah_cost (after a refit they differ)
    std::size_t node_bytes = 0, leaf_object_bytes = 0;
    std::size_t objects = 0;  // the BVH's object count, the "per object" denominator
    std::size_t total_bytes() const { return node_bytes + leaf_object_bytes; }
    // Bytes per object (per triangle in a mesh scene); 0 for a BVH over no objects.
    double per_object(std::size_t bytes) const {
        return objects ? static_cast<double>(bytes) / static_cast<double>(objects) : 0.0;
    }
};

}  // namespace kdrt
