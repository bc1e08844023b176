#include "scene/model_header_check.h"

#include <charconv>
#include <map>
#include <sstream>
#include <string_view>
#include <vector>

namespace kdrt::detail {
namespace {

// Bytes of each scalar type in a binary body.
const std::map<std::string, unsigned>& scalar_sizes() {
    static const std::map<std::string, unsigned> sizes{
        {"char", 1},  {"uchar", 1},  {"int8", 1},  {"uint8", 1},   {"short", 2},   {"ushort", 2},
        {"int16", 2}, {"uint16", 2}, {"int", 4},   {"uint", 4},    {"int32", 4},   {"uint32", 4},
        {"float", 4}, {"float32", 4}, {"double", 8}, {"float64", 8}};
    return sizes;
}

// One property of an element: a scalar, or a list (its length's bytes, then
// that many items).
struct Property {
    unsigned bytes = 0;       // the scalar, or the list's length field
    unsigned item_bytes = 0;  // lists only: each item; 0 for a scalar
};

struct Element {
    std::string name;
    std::uint64_t count = 0;
    std::uint64_t min_binary_bytes = 0;  // one record, lists empty
    std::uint64_t fields = 0;            // scalars and list lengths in one record
    std::vector<Property> properties;
};

struct PlyHeader {
    bool ascii = false;
    bool big_endian = false;
    std::size_t body = 0;  // offset of the first byte after the end_header line
    std::vector<Element> elements;
};

std::vector<std::string> words(const std::string& line) {
    std::istringstream in(line);
    std::vector<std::string> w;
    for (std::string s; in >> s;) w.push_back(s);
    return w;
}

// Parses the header into `out`; returns what is wrong with it, or empty.
std::string parse_ply_header(std::string_view head, std::uintmax_t file_size, PlyHeader& out) {
    // end_header on a line of its own (Assimp's reader loops on "propend_header").
    std::size_t end = head.find("\nend_header");
    while (end != std::string::npos) {
        const std::size_t after = head.find_first_not_of(" \t\r", end + 11);
        if (after == std::string::npos || head[after] == '\n') break;
        end = head.find("\nend_header", end + 1);
    }
    if (end != std::string::npos) ++end;
    if (end == std::string::npos)
        return head.size() >= file_size ? "PLY header has no end_header line (file truncated?)"
                                        : "PLY header longer than 1 MiB or without end_header";
    std::size_t body = head.find('\n', end);
    if (body == std::string::npos) return "PLY header has no end_header line (file truncated?)";
    ++body;

    std::istringstream lines(std::string(head.substr(0, end)));
    std::string line;
    std::getline(lines, line);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line != "ply" && line != "PLY") return "not a PLY file (the first line must be 'ply')";
    bool have_format = false;
    out.body = body;
    std::vector<Element>& elements = out.elements;
    int number = 1;
    while (std::getline(lines, line)) {
        ++number;
        const std::string at = "PLY header line " + std::to_string(number) + ": ";
        const std::vector<std::string> w = words(line);
        if (w.empty()) continue;
        if (w[0] == "comment" || w[0] == "obj_info") continue;
        if (w[0] == "format") {
            if (w.size() != 3 || w[2] != "1.0" ||
                (w[1] != "ascii" && w[1] != "binary_little_endian" && w[1] != "binary_big_endian"))
                return at + "expected 'format ascii|binary_little_endian|binary_big_endian 1.0'";
            out.ascii = w[1] == "ascii";
            out.big_endian = w[1] == "binary_big_endian";
            have_format = true;
        } else if (w[0] == "element") {
            Element e;
            if (w.size() != 3) return at + "expected 'element NAME COUNT'";
            const auto [ptr, ec] = std::from_chars(w[2].data(), w[2].data() + w[2].size(), e.count);
            if (ec != std::errc() || ptr != w[2].data() + w[2].size() || e.count > 0xffffffffu)
                return at + "element count '" + w[2] + "' is not a number below 2^32";
            e.name = w[1];
            elements.push_back(e);
        } else if (w[0] == "property") {
            if (elements.empty()) return at + "property before any element";
            Element& e = elements.back();
            const auto& sizes = scalar_sizes();
            if (w.size() == 5 && w[1] == "list") {
                auto count_type = sizes.find(w[2]);
                auto item_type = sizes.find(w[3]);
                if (count_type == sizes.end() || item_type == sizes.end()) return at + "unknown list type";
                e.min_binary_bytes += count_type->second;
                e.properties.push_back({count_type->second, item_type->second});
            } else if (w.size() == 3) {
                auto type = sizes.find(w[1]);
                if (type == sizes.end()) return at + "unknown property type '" + w[1] + "'";
                e.min_binary_bytes += type->second;
                e.properties.push_back({type->second, 0});
            } else {
                return at + "expected 'property TYPE NAME' or 'property list TYPE TYPE NAME'";
            }
            ++e.fields;
        }
        // Other lines are skipped, as Assimp does: old Blender wrote comments without "comment".
    }
    if (!have_format) return "PLY header has no format line";
    return {};
}

}  // namespace

std::string ply_header_problem(const std::string& head, std::uintmax_t file_size) {
    PlyHeader header;
    if (std::string problem = parse_ply_header(head, file_size, header); !problem.empty()) return problem;
    const bool ascii = header.ascii;
    const std::size_t body = header.body;
    const std::vector<Element>& elements = header.elements;

    // The counts must fit in what follows the header: a binary record takes at
    // least its fixed size, an ASCII one at least 2 bytes per field ("0 ").
    const std::uintmax_t available = file_size > body ? file_size - body : 0;
    long double needed = 0;
    for (const Element& e : elements)
        needed += static_cast<long double>(e.count) * static_cast<long double>(ascii ? 2 * e.fields - (e.fields > 0) : e.min_binary_bytes);
    if (needed > static_cast<long double>(available))
        return "PLY element counts need at least " + std::to_string(static_cast<std::uintmax_t>(needed)) +
               " bytes after the header but the file has " + std::to_string(available) + " (truncated?)";
    return {};
}

std::string off_header_problem(const std::string& head, std::uintmax_t file_size) {
    // The first tokens, '#' comments skipped: [keyword] [dimension] vertices faces edges.
    std::vector<std::string> tokens;
    std::istringstream lines(head);
    for (std::string line; tokens.size() < 6 && std::getline(lines, line);) {
        line = line.substr(0, line.find('#'));
        for (const std::string& w : words(line)) tokens.push_back(w);
    }
    std::size_t at = 0;
    if (!tokens.empty() && tokens[0].find("OFF") != std::string::npos) {
        if (tokens[0].back() != 'F') return "OFF header: unknown keyword '" + tokens[0] + "'";
        at = tokens[0].find("nOFF") != std::string::npos ? 2 : 1;  // nOFF: a dimension follows
    }
    if (tokens.size() < at + 2) return "OFF header: expected the vertex and face counts";
    std::uint64_t count[2] = {0, 0};
    for (int i = 0; i < 2; ++i) {
        const std::string& t = tokens[at + static_cast<std::size_t>(i)];
        const auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), count[i]);
        if (ec != std::errc() || ptr != t.data() + t.size() || count[i] > 0xffffffffu)
            return "OFF header: count '" + t + "' is not a number below 2^32";
    }
    // A vertex takes at least "0 0 0\n", a face at least "3 0 1 2\n".
    const long double needed = 6.0L * count[0] + 8.0L * count[1];
    if (needed > static_cast<long double>(file_size) + 8.0L)
        return "OFF header: " + std::to_string(count[0]) + " vertices and " + std::to_string(count[1]) +
               " faces do not fit in a file of " + std::to_string(file_size) + " bytes (truncated?)";
    return {};
}

namespace {

// A binary list length of `bytes` bytes at `p`, in the file's byte order;
// signed types read as their two's complement (a negative length is huge).
std::uint64_t binary_count(const char* p, unsigned bytes, bool big_endian) {
    std::uint64_t v = 0;
    for (unsigned i = 0; i < bytes; ++i) {
        const unsigned char byte = static_cast<unsigned char>(p[big_endian ? i : bytes - 1 - i]);
        v = (v << 8) | byte;
    }
    return v;
}

std::string record_place(const Element& e, std::uint64_t record) {
    return "PLY element '" + e.name + "' " + std::to_string(record) + ": ";
}

std::string binary_body_problem(std::string_view file, const PlyHeader& h) {
    std::size_t at = h.body;
    for (const Element& e : h.elements) {
        for (std::uint64_t r = 0; r < e.count; ++r) {
            for (const Property& p : e.properties) {
                if (file.size() - at < p.bytes) return record_place(e, r) + "the file ends inside it (truncated?)";
                if (p.item_bytes == 0) {
                    at += p.bytes;
                    continue;
                }
                const std::uint64_t n = binary_count(file.data() + at, p.bytes, h.big_endian);
                at += p.bytes;
                if (n > (file.size() - at) / p.item_bytes)
                    return record_place(e, r) + "a list of " + std::to_string(n) + " items does not fit in the " +
                           std::to_string(file.size() - at) + " bytes left";
                at += static_cast<std::size_t>(n) * p.item_bytes;
            }
        }
    }
    return {};
}

std::string ascii_body_problem(std::string_view file, const PlyHeader& h) {
    std::size_t at = h.body;
    const auto space = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; };
    const auto next_token = [&]() -> std::string_view {
        while (at < file.size() && space(file[at])) ++at;
        const std::size_t start = at;
        while (at < file.size() && !space(file[at])) ++at;
        return file.substr(start, at - start);
    };
    for (const Element& e : h.elements) {
        for (std::uint64_t r = 0; r < e.count; ++r) {
            for (const Property& p : e.properties) {
                const std::string_view token = next_token();
                if (token.empty()) return record_place(e, r) + "the file ends inside it (truncated?)";
                if (p.item_bytes == 0) continue;
                // Each item takes at least two bytes ("0 "): a longer list is a damaged count.
                std::uint64_t n = 0;
                const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), n);
                if (ec != std::errc() || ptr != token.data() + token.size())
                    return record_place(e, r) + "list length '" + std::string(token.substr(0, 32)) +
                           "' is not a count";
                if (n > (file.size() - at) / 2)
                    return record_place(e, r) + "a list of " + std::to_string(n) + " items does not fit in the " +
                           std::to_string(file.size() - at) + " bytes left";
                for (std::uint64_t k = 0; k < n; ++k)
                    if (next_token().empty()) return record_place(e, r) + "the file ends inside a list (truncated?)";
            }
        }
    }
    return {};
}

}  // namespace

std::string ply_body_problem(std::string_view file) {
    PlyHeader header;
    const std::string_view head = file.substr(0, kHeaderLimit);
    if (std::string problem = parse_ply_header(head, file.size(), header); !problem.empty()) return problem;
    return header.ascii ? ascii_body_problem(file, header) : binary_body_problem(file, header);
}

}  // namespace kdrt::detail
