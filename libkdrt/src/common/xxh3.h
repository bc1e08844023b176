// XXH3 (libxxhash): the one non-cryptographic hash libkdrt uses (tree-file
// checksums, scene-geometry fingerprints and digests). Byte-order independent as long as
// the caller feeds bytes in a fixed order; gigabytes per second, where the
// byte-wise FNV-1a it replaced spent seconds on a large tree file.
#pragma once

#include <xxhash.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>

namespace kdrt::detail {

// Streaming XXH3-64 with seed 0: update() pieces in order, then digest().
class Xxh3 {
public:
    Xxh3() : state_(XXH3_createState()) {
        if (!state_ || XXH3_64bits_reset(state_.get()) != XXH_OK) throw std::bad_alloc();
    }
    void update(const void* data, std::size_t size) {
        if (size) XXH3_64bits_update(state_.get(), data, size);
    }
    std::uint64_t digest() const { return XXH3_64bits_digest(state_.get()); }

private:
    struct Free {
        void operator()(XXH3_state_t* s) const { XXH3_freeState(s); }
    };
    std::unique_ptr<XXH3_state_t, Free> state_;
};

// Streaming XXH3-128 with seed 0, for digests that stand in for an equality
// test of large inputs (CommittedScene::update()'s geometry check).
class Xxh3x128 {
public:
    Xxh3x128() : state_(XXH3_createState()) {
        if (!state_ || XXH3_128bits_reset(state_.get()) != XXH_OK) throw std::bad_alloc();
    }
    void update(const void* data, std::size_t size) {
        if (size) XXH3_128bits_update(state_.get(), data, size);
    }
    XXH128_hash_t digest() const { return XXH3_128bits_digest(state_.get()); }

private:
    struct Free {
        void operator()(XXH3_state_t* s) const { XXH3_freeState(s); }
    };
    std::unique_ptr<XXH3_state_t, Free> state_;
};

}  // namespace kdrt::detail
