// Mailbox: the objects one ray has already been tested against, so that an
// object referenced by several leaves is tested once (mailboxing, Amanatides
// and Woo 1987). Instead of a per-object ray stamp, which would make tracing
// write to the scene, each ray keeps a small direct-mapped cache of object ids:
// a collision only costs a repeated test, never a different result, because
// testing an object again gives exactly what the first test gave.
// Trees in which no object is in two leaves have nothing to gain: they use
// NoMailbox (the kernels: compiled without KDRT_MAILBOX), which costs nothing.
// The OpenCL twin is Mailbox in cl/common.cl.
#pragma once

#include "cpu/cpu_isa.h"
#include "device/kernel_records.h"

#include <kdrt/kd_tree.h>

#include <cstdint>

namespace kdrt::detail::inline KDRT_CPU_ISA {

struct Mailbox {
    std::uint32_t ids[KDRT_MAILBOX_SIZE];

    Mailbox() {
        for (std::uint32_t& id : ids) id = KDRT_MAILBOX_EMPTY;
    }
    // True when `id` was tested already; records it otherwise.
    bool seen(std::uint32_t id) {
        std::uint32_t& slot = ids[id & (KDRT_MAILBOX_SIZE - 1)];
        if (slot == id) return true;
        slot = id;
        return false;
    }
};

struct NoMailbox {
    bool seen(std::uint32_t) const { return false; }
};

// Whether a tree references some object from more than one leaf.
inline bool tree_duplicates_objects(const KdTree* tree) {
    return tree && tree->leaf_objects.size() > tree->object_count;
}

}  // namespace kdrt::detail::KDRT_CPU_ISA
