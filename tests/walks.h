// The ways a committed scene can be walked: a structure and one of its
// traversals, for tests that run on every one of them.
#pragma once

#include <kdrt/commit_options.h>

#include <ostream>

namespace kdrt_test {

struct Walk {
    kdrt::Accel accel;
    kdrt::Traversal traversal;

    void apply(kdrt::CommitOptions& o) const {
        o.accel = accel;
        o.traversal = traversal;
    }
    friend std::ostream& operator<<(std::ostream& os, const Walk& w) {
        return os << kdrt::to_string(w.accel) << " " << kdrt::to_string(w.traversal);
    }
};

// The kd-tree's five traversals and the BVH's stack traversal.
inline constexpr Walk kAllWalks[] = {{kdrt::Accel::KdTree, kdrt::Traversal::None},
                                     {kdrt::Accel::KdTree, kdrt::Traversal::Restart},
                                     {kdrt::Accel::KdTree, kdrt::Traversal::Ropes},
                                     {kdrt::Accel::KdTree, kdrt::Traversal::Stack},
                                     {kdrt::Accel::KdTree, kdrt::Traversal::ShortStack},
                                     {kdrt::Accel::Bvh, kdrt::Traversal::Stack}};

// Every walk that prunes by a query's bound: all but the kd-tree's brute force.
inline constexpr Walk kPrunedWalks[] = {{kdrt::Accel::KdTree, kdrt::Traversal::Restart},
                                        {kdrt::Accel::KdTree, kdrt::Traversal::Ropes},
                                        {kdrt::Accel::KdTree, kdrt::Traversal::Stack},
                                        {kdrt::Accel::KdTree, kdrt::Traversal::ShortStack},
                                        {kdrt::Accel::Bvh, kdrt::Traversal::Stack}};

}  // namespace kdrt_test
