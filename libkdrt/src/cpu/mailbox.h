// Mailbox: the objects one ray has already been tested against, so that an
// object referenced by several leaves is tested once (mailboxing, Amanatides
// and Woo 1987). Instead of a per-object ray stamp, which would make tracing
// write to the scene, each ray keeps a small direct-mapped cache of object ids:
// a collision only costs a repeated test, never a different result, because
// testing an object again gives exactly what the first test gave.
// The OpenCL twin is Mailbox in cl/common.cl.
#pragma once

#include <kdrt/shared/kdrt_shared.h>

#include <cstdint>

namespace kdrt::detail {

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

}  // namespace kdrt::detail
