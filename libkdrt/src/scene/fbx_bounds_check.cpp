#include "scene/fbx_bounds_check.h"

#include <cstdint>
#include <vector>

namespace kdrt::detail {
namespace {

constexpr std::string_view kBinaryMagic{"Kaydara FBX Binary  \0\x1a\0", 23};
constexpr std::uint64_t kDeflateMaxRatio = 1032;

std::uint64_t le(std::string_view bytes, std::size_t at, unsigned size) {
    std::uint64_t v = 0;
    for (unsigned i = size; i-- > 0;) v = (v << 8) | static_cast<unsigned char>(bytes[at + i]);
    return v;
}

std::string at_byte(std::size_t at) { return "FBX record at byte " + std::to_string(at) + ": "; }

// The properties of one record, [begin, end) of the file.
std::string properties_problem(std::string_view file, std::size_t begin, std::size_t end, std::uint64_t count) {
    std::size_t at = begin;
    for (std::uint64_t i = 0; i < count; ++i) {
        if (at >= end) return at_byte(begin) + "more properties than its property list holds";
        const char type = file[at++];
        const auto need = [&](std::uint64_t n) { return n <= end - at; };
        std::uint64_t scalar = 0;
        switch (type) {
            case 'C': scalar = 1; break;
            case 'Y': scalar = 2; break;
            case 'I': case 'F': scalar = 4; break;
            case 'D': case 'L': scalar = 8; break;
            case 'S': case 'R':
                if (!need(4) || !need(4 + le(file, at, 4))) return at_byte(begin) + "a string runs past its record";
                at += 4 + le(file, at, 4);
                continue;
            case 'f': case 'i': case 'b': case 'c': case 'd': case 'l': {
                if (!need(12)) return at_byte(begin) + "an array header runs past its record";
                const std::uint64_t length = le(file, at, 4), encoding = le(file, at + 4, 4), stored = le(file, at + 8, 4);
                at += 12;
                if (!need(stored)) return at_byte(begin) + "an array's data runs past its record";
                const std::uint64_t element = (type == 'b' || type == 'c') ? 1 : (type == 'd' || type == 'l') ? 8 : 4;
                const long double bytes = static_cast<long double>(length) * element;
                if (encoding == 0 && bytes != static_cast<long double>(stored))
                    return at_byte(begin) + "an array of " + std::to_string(length) + " elements holds " +
                           std::to_string(stored) + " bytes";
                if (encoding == 1 && bytes > static_cast<long double>(stored) * kDeflateMaxRatio)
                    return at_byte(begin) + "an array of " + std::to_string(length) + " elements cannot inflate from " +
                           std::to_string(stored) + " bytes";
                if (encoding > 1) return at_byte(begin) + "an array of unknown encoding " + std::to_string(encoding);
                at += stored;
                continue;
            }
            default:
                return at_byte(begin) + "unknown property type " + std::to_string(static_cast<unsigned char>(type));
        }
        if (!need(scalar)) return at_byte(begin) + "a property runs past its record";
        at += scalar;
    }
    return {};
}

// Records are walked with an explicit stack of the enclosing records' ends.
std::string binary_problem(std::string_view file) {
    if (file.size() < 27) return "FBX binary header cut short";
    const bool wide = le(file, 23, 4) >= 7500;  // 64-bit offsets and counts
    const unsigned field = wide ? 8 : 4;
    const std::size_t header = 3 * field + 1;
    std::vector<std::size_t> ends{file.size()};
    std::size_t at = 27;
    while (!ends.empty()) {
        const std::size_t limit = ends.back();
        if (at == limit) {  // a parent's children that fill it exactly
            ends.pop_back();
            continue;
        }
        if (limit - at < header) {
            if (ends.size() == 1) return {};  // the top level ends in a footer
            return at_byte(at) + "cut short";
        }
        const std::uint64_t end = le(file, at, field), count = le(file, at + field, field),
                            list = le(file, at + 2 * field, field);
        const unsigned name = static_cast<unsigned char>(file[at + 3 * field]);
        if (end == 0) {  // a null record closes the enclosing record's children
            at += header;
            ends.pop_back();
            if (!ends.empty()) at = limit;
            continue;
        }
        const std::size_t body = at + header + name;
        if (end > limit || end < body || list > end - body)
            return at_byte(at) + "its end (" + std::to_string(end) + ") or property list lies outside " +
                   (ends.size() == 1 ? std::string("the file") : "its parent record");
        if (std::string problem = properties_problem(file, body, body + list, count); !problem.empty()) return problem;
        at = body + list;
        if (at < end) {
            if (ends.size() > kMaxFbxDepth) return at_byte(at) + "records nested deeper than " + std::to_string(kMaxFbxDepth);
            ends.push_back(end);
        }
    }
    return {};
}

std::string text_problem(std::string_view file) {
    std::size_t depth = 0;
    for (std::size_t i = 0; i < file.size(); ++i) {
        const char c = file[i];
        if (c == ';') {
            while (i < file.size() && file[i] != '\n') ++i;
        } else if (c == '"') {
            for (++i; i < file.size() && file[i] != '"' && file[i] != '\n'; ++i) {}
        } else if (c == '{') {
            if (++depth > kMaxFbxDepth) return "FBX braces nested deeper than " + std::to_string(kMaxFbxDepth) + " levels";
        } else if (c == '}') {
            if (depth > 0) --depth;
        } else if (c == '*' && i + 1 < file.size() && file[i + 1] >= '0' && file[i + 1] <= '9') {
            std::uint64_t count = 0;
            std::size_t j = i + 1;
            for (; j < file.size() && file[j] >= '0' && file[j] <= '9' && count < (1ull << 40); ++j)
                count = count * 10 + static_cast<unsigned>(file[j] - '0');
            // Each element takes at least two bytes ("0,").
            if (count > (file.size() - j) / 2)
                return "FBX array at byte " + std::to_string(i) + " declares " + std::to_string(count) +
                       " elements, more than the " + std::to_string(file.size() - j) + " bytes left hold";
            i = j - 1;
        }
    }
    return {};
}

}  // namespace

std::string fbx_bounds_problem(std::string_view file) {
    return file.substr(0, kBinaryMagic.size()) == kBinaryMagic ? binary_problem(file) : text_problem(file);
}

}  // namespace kdrt::detail
