#include "image/netpbm.h"

#include <kdrt/error.h>

#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>

namespace kdrt::detail {

namespace {

std::string header(const char* magic, int width, int height, const char* last) {
    return std::string(magic) + "\n" + std::to_string(width) + " " + std::to_string(height) + "\n" + last + "\n";
}

// The header's fields: whitespace separated, '#' comments to the end of the
// line, exactly one whitespace character after the last one.
class HeaderReader {
public:
    HeaderReader(std::string_view bytes, const std::string& name) : bytes_(bytes), name_(name) {}

    std::string_view token() {
        for (;;) {
            while (at_ < bytes_.size() && std::isspace(static_cast<unsigned char>(bytes_[at_]))) ++at_;
            if (at_ < bytes_.size() && bytes_[at_] == '#') {
                while (at_ < bytes_.size() && bytes_[at_] != '\n') ++at_;
                continue;
            }
            break;
        }
        const std::size_t start = at_;
        while (at_ < bytes_.size() && !std::isspace(static_cast<unsigned char>(bytes_[at_]))) ++at_;
        if (start == at_) fail("truncated header");
        return bytes_.substr(start, at_ - start);
    }
    long integer(long low, long high, const char* what) {
        const std::string_view t = token();
        long v = 0;
        const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
        if (ec != std::errc() || end != t.data() + t.size() || v < low || v > high)
            fail(std::string("bad ") + what + " '" + std::string(t.substr(0, 32)) + "'");
        return v;
    }
    double real(const char* what) {
        const std::string_view t = token();
        double v = 0;
        const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
        if (ec != std::errc() || end != t.data() + t.size() || !std::isfinite(v) || v == 0.0)
            fail(std::string("bad ") + what + " '" + std::string(t.substr(0, 32)) + "'");
        return v;
    }
    // The samples start after the single whitespace character ending the header.
    std::string_view samples(std::size_t size) {
        if (at_ >= bytes_.size()) fail("truncated header");
        ++at_;
        if (bytes_.size() - at_ < size)
            fail("truncated: " + std::to_string(size) + " bytes of samples expected, " +
                 std::to_string(bytes_.size() - at_) + " present");
        return bytes_.substr(at_, size);
    }
    [[noreturn]] void fail(const std::string& what) const {
        throw Error(ErrorCode::Io, name_ + ": cannot read image: " + what);
    }

private:
    std::string_view bytes_;
    const std::string& name_;
    std::size_t at_ = 0;
};

constexpr long kMaxSide = 1 << 20;

}  // namespace

std::vector<unsigned char> encode_ppm(const unsigned char* rgb, int width, int height) {
    const std::string head = header("P6", width, height, "255");
    std::vector<unsigned char> out(head.begin(), head.end());
    out.insert(out.end(), rgb, rgb + static_cast<std::size_t>(width) * height * 3);
    return out;
}

std::vector<unsigned char> encode_pfm(const float* rgb, int width, int height) {
    const std::string head = header("PF", width, height, "-1.0");
    std::vector<unsigned char> out(head.begin(), head.end());
    const std::size_t row = static_cast<std::size_t>(width) * 3;
    out.reserve(out.size() + row * height * 4);
    for (int y = height - 1; y >= 0; --y)
        for (std::size_t i = 0; i < row; ++i) {
            const std::uint32_t bits = std::bit_cast<std::uint32_t>(rgb[y * row + i]);
            for (int b = 0; b < 4; ++b) out.push_back(static_cast<unsigned char>(bits >> (8 * b)));
        }
    return out;
}

Image decode_netpbm(std::string_view bytes, const std::string& name) {
    HeaderReader h(bytes, name);
    const std::string_view magic = h.token();
    const bool pfm = magic == "PF" || magic == "Pf", ppm = magic == "P6" || magic == "P5";
    if (!pfm && !ppm) h.fail("not a binary PPM/PGM or PFM file");
    const int channels = magic == "PF" || magic == "P6" ? 3 : 1;
    const int width = static_cast<int>(h.integer(1, kMaxSide, "width"));
    const int height = static_cast<int>(h.integer(1, kMaxSide, "height"));
    const std::size_t count = static_cast<std::size_t>(width) * height * channels;
    Image image(width, height);
    auto store = [&](std::size_t i, float v) {  // sample i of the file, rows in file order
        const std::size_t pixel = i / channels;
        std::size_t y = pixel / width;
        if (pfm) y = height - 1 - y;  // PFM rows go bottom to top
        const std::size_t at = (y * width + pixel % width) * 3;
        if (channels == 3)
            image.rgb[at + i % 3] = v;
        else
            image.rgb[at] = image.rgb[at + 1] = image.rgb[at + 2] = v;
    };
    if (pfm) {
        const bool little = h.real("scale") < 0;
        const std::string_view s = h.samples(count * 4);
        for (std::size_t i = 0; i < count; ++i) {
            std::uint32_t bits = 0;
            for (int b = 0; b < 4; ++b) {
                const auto byte = static_cast<std::uint32_t>(static_cast<unsigned char>(s[i * 4 + b]));
                bits |= byte << (little ? 8 * b : 8 * (3 - b));
            }
            store(i, std::bit_cast<float>(bits));
        }
    } else {
        const long maxval = h.integer(1, 65535, "maximum value");
        const int size = maxval > 255 ? 2 : 1;
        const std::string_view s = h.samples(count * size);
        for (std::size_t i = 0; i < count; ++i) {
            const auto* p = reinterpret_cast<const unsigned char*>(s.data()) + i * size;
            const long v = size == 2 ? p[0] * 256L + p[1] : p[0];
            if (v > maxval) h.fail("a sample exceeds the maximum value");
            store(i, static_cast<float>(v) / static_cast<float>(maxval));
        }
    }
    return image;
}

}  // namespace kdrt::detail
