// Ropes: for every leaf and each of its six faces, the node on the other side
// of that face, after S. Popov, J. Guenther, H.-P. Seidel, P. Slusallek,
// "Stackless KD-Tree Traversal for High Performance GPU Ray Tracing",
// Eurographics 2007 (itself after Havran's neighbour links).
//
// The ropes are passed down the tree: at an inner node splitting axis a, the
// below child's +a rope is the above child and the above child's -a rope is
// the below child; the other ropes are inherited. At every node each rope is
// first "optimised" (Popov et al.'s Optimize) against the node's cell: it is
// pushed down to the deepest node whose cell still covers the whole face, so a
// rope traversal lands as close to its target leaf as possible:
//  - a split plane parallel to the face: go to the child adjacent to the face;
//  - a split plane across the face: go to the child holding all of the face,
//    and stop where the plane cuts through the face.
// The scene boundary has no rope (KDRT_ROPE_NONE).
#include <kdrt/kd_tree.h>

#include <array>
#include <vector>

namespace kdrt {

namespace {

using Ropes = std::array<std::uint32_t, 6>;  // -x, +x, -y, +y, -z, +z

// Pushes the rope of face `face` of `cell` down to the deepest node covering the face.
std::uint32_t optimise(const KdTree& tree, std::uint32_t rope, int face, const Aabb& cell) {
    const int face_axis = face / 2;
    const bool positive = (face & 1) != 0;
    while (rope != KDRT_ROPE_NONE && !kd_is_leaf(tree.nodes[rope])) {
        const KdNode& n = tree.nodes[rope];
        const int axis = kd_axis(n);
        const double split = kd_split(n);
        if (axis == face_axis) {
            // The rope's node lies beyond the face: its child touching the
            // face is the below one for a +a face, the above one for a -a face.
            rope = positive ? rope + 1 : kd_above_child(n);
        } else if (cell.hi[axis] <= split) {
            rope = rope + 1;
        } else if (cell.lo[axis] >= split) {
            rope = kd_above_child(n);
        } else {
            break;
        }
    }
    return rope;
}

}  // namespace

void build_ropes(KdTree& tree) {
    tree.ropes.assign(tree.nodes.size(), KdLeafRopes{});  // by node id: the traversal needs no leaf number
    if (tree.nodes.empty()) return;

    struct Item {
        std::uint32_t node;
        Aabb cell;
        Ropes ropes;
    };
    std::vector<Item> stack;  // depth-first; at most max_depth + 1 entries deep in practice
    Ropes none;
    none.fill(KDRT_ROPE_NONE);
    stack.push_back({0, tree.bounds, none});
    while (!stack.empty()) {
        Item item = stack.back();
        stack.pop_back();
        for (int face = 0; face < 6; ++face) item.ropes[face] = optimise(tree, item.ropes[face], face, item.cell);

        const KdNode& n = tree.nodes[item.node];
        if (kd_is_leaf(n)) {
            KdLeafRopes& out = tree.ropes[item.node];
            for (int face = 0; face < 6; ++face) out.rope[face] = item.ropes[face];
            for (int k = 0; k < 3; ++k) {  // the cells are float-representable, so this is exact
                out.box_min[k] = static_cast<float>(item.cell.lo[k]);
                out.box_max[k] = static_cast<float>(item.cell.hi[k]);
            }
            continue;
        }
        const int axis = kd_axis(n);
        const std::uint32_t below = item.node + 1, above = kd_above_child(n);
        Item b = item, a = item;
        b.node = below;
        b.cell.hi[axis] = kd_split(n);
        b.ropes[2 * axis + 1] = above;
        a.node = above;
        a.cell.lo[axis] = kd_split(n);
        a.ropes[2 * axis] = below;
        stack.push_back(a);
        stack.push_back(b);
    }
}

}  // namespace kdrt
