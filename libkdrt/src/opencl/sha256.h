// SHA-256 (FIPS 180-4), small and dependency-free: the program cache's key
// and the checksum of the binaries it stores.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace kdrt::detail::ocl {

using Sha256Digest = std::array<std::uint8_t, 32>;

class Sha256 {
public:
    Sha256();
    void update(const void* data, std::size_t size);
    void update(std::string_view text) { update(text.data(), text.size()); }
    // Pads, returns the digest and leaves the object reset for a new message.
    Sha256Digest finish();

private:
    void compress(const std::uint8_t* block);

    std::array<std::uint32_t, 8> state_;
    std::array<std::uint8_t, 64> buffer_;
    std::size_t buffered_ = 0;
    std::uint64_t total_bytes_ = 0;
};

Sha256Digest sha256(const void* data, std::size_t size);
Sha256Digest sha256(std::string_view text);
// HMAC-SHA-256 (RFC 2104) with a 32-byte key.
Sha256Digest hmac_sha256(const Sha256Digest& key, const void* data, std::size_t size);
std::string to_hex(const Sha256Digest& digest);  // 64 lowercase hex digits

}  // namespace kdrt::detail::ocl
