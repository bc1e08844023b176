#include "scene/model_header_check.h"

#include <charconv>
#include <map>
#include <sstream>
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

struct Element {
    std::string name;
    std::uint64_t count = 0;
    std::uint64_t min_binary_bytes = 0;  // one record, lists empty
    std::uint64_t fields = 0;            // scalars and list lengths in one record
};

std::vector<std::string> words(const std::string& line) {
    std::istringstream in(line);
    std::vector<std::string> w;
    for (std::string s; in >> s;) w.push_back(s);
    return w;
}

}  // namespace

std::string ply_header_problem(const std::string& head, std::uintmax_t file_size) {
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

    std::istringstream lines(head.substr(0, end));
    std::string line;
    std::getline(lines, line);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line != "ply" && line != "PLY") return "not a PLY file (the first line must be 'ply')";
    bool ascii = false, have_format = false;
    std::vector<Element> elements;
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
            ascii = w[1] == "ascii";
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
                if (count_type == sizes.end() || sizes.count(w[3]) == 0) return at + "unknown list type";
                e.min_binary_bytes += count_type->second;
            } else if (w.size() == 3) {
                auto type = sizes.find(w[1]);
                if (type == sizes.end()) return at + "unknown property type '" + w[1] + "'";
                e.min_binary_bytes += type->second;
            } else {
                return at + "expected 'property TYPE NAME' or 'property list TYPE TYPE NAME'";
            }
            ++e.fields;
        }
        // Other lines are skipped, as Assimp does: old Blender wrote comments without "comment".
    }
    if (!have_format) return "PLY header has no format line";

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

}  // namespace kdrt::detail
