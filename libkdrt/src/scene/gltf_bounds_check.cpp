#include "scene/gltf_bounds_check.h"

#include "scene/json_depth.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cstring>
#include <map>
#include <optional>
#include <system_error>
#include <utility>
#include <vector>

namespace kdrt::detail {
namespace {

using Json = nlohmann::json;

std::uint32_t le32(const char* p) {
    std::uint32_t v = 0;
    for (int i = 3; i >= 0; --i) v = (v << 8) | static_cast<unsigned char>(p[i]);
    return v;
}

// The JSON text of a .glb and the bytes of its BIN chunk (buffer 0 without
// a URI), or a problem with its chunk structure.
struct GlbParts {
    std::string_view json, bin;
    std::string problem;
};

GlbParts split_glb(std::string_view file) {
    GlbParts out;
    if (file.size() < 20 || file.substr(0, 4) != "glTF") {
        out.problem = "not a binary glTF file (no 'glTF' header)";
        return out;
    }
    const std::uint32_t version = le32(file.data() + 4), length = le32(file.data() + 8);
    if (length > file.size())
        return {{}, {}, "GLB header declares " + std::to_string(length) + " bytes, the file has " + std::to_string(file.size())};
    const std::uint32_t json_length = le32(file.data() + 12);
    if (version == 1) {  // glTF 1.0: content length, content format, JSON, body
        if (json_length > length - 20)
            return {{}, {}, "GLB content of " + std::to_string(json_length) + " bytes does not fit in the file"};
        out.json = file.substr(20, json_length);
        out.bin = file.substr(20 + json_length, length - 20 - json_length);
        return out;
    }
    if (json_length > length - 20)
        return {{}, {}, "GLB JSON chunk of " + std::to_string(json_length) + " bytes does not fit in the file"};
    if (le32(file.data() + 16) != 0x4E4F534Au) return {{}, {}, "GLB: the first chunk is not JSON"};
    out.json = file.substr(20, json_length);
    const std::size_t next = 20 + static_cast<std::size_t>(json_length);
    if (length - next >= 8) {
        const std::uint32_t bin_length = le32(file.data() + next);
        if (bin_length > length - next - 8)
            return {{}, {}, "GLB chunk of " + std::to_string(bin_length) + " bytes does not fit in the file (" +
                                std::to_string(length - next - 8) + " bytes left)"};
        out.bin = file.substr(next + 8, bin_length);
    }
    return out;
}

// glTF 2.0 lists nodes in an array, glTF 1.0 in an object by id: both as
// children lists of indices.
std::vector<std::vector<std::size_t>> node_children(const Json& doc) {
    std::vector<std::vector<std::size_t>> children;
    const auto nodes = doc.find("nodes");
    if (nodes == doc.end()) return children;
    std::map<std::string, std::size_t> by_id;
    if (nodes->is_object())
        for (const auto& [id, node] : nodes->items()) by_id.emplace(id, by_id.size());
    children.resize(nodes->size());
    std::size_t i = 0;
    for (const auto& node : *nodes) {
        const auto list = node.is_object() ? node.find("children") : node.end();
        if (list != node.end() && list->is_array())
            for (const Json& c : *list) {
                if (c.is_number_unsigned() && c.get<std::uint64_t>() < children.size())
                    children[i].push_back(c.get<std::size_t>());
                else if (c.is_string() && by_id.count(c.get<std::string>()))
                    children[i].push_back(by_id[c.get<std::string>()]);
            }
        ++i;
    }
    return children;
}

// Per node: how many copies of it and its subtree a converter that copies
// shared children makes (saturating), and the levels below it. Iterative
// post-order: the node tree may be as deep as the file is long.
std::string node_graph_problem(const std::vector<std::vector<std::size_t>>& children, std::vector<std::uint64_t>& copies) {
    const std::size_t n = children.size();
    std::vector<std::uint32_t> depth(n, 0);
    std::vector<char> state(n, 0);  // 0 new, 1 open, 2 done
    copies.assign(n, 0);
    for (std::size_t root = 0; root < n; ++root) {
        if (state[root]) continue;
        std::vector<std::pair<std::size_t, std::size_t>> stack{{root, 0}};  // node, next child
        state[root] = 1;
        while (!stack.empty()) {
            auto& [node, next] = stack.back();
            if (next < children[node].size()) {
                const std::size_t child = children[node][next++];
                if (state[child] == 1) return "glTF node " + std::to_string(child) + " is its own ancestor (a cycle)";
                if (state[child] == 0) {
                    state[child] = 1;
                    stack.emplace_back(child, 0);
                }
                continue;
            }
            std::uint64_t total = 1;
            std::uint32_t below = 0;
            for (std::size_t c : children[node]) {
                total = std::min(total + copies[c], kMaxGltfNodeInstances + 1);
                below = std::max(below, depth[c]);
            }
            copies[node] = total;
            depth[node] = below + 1;
            if (depth[node] > kMaxGltfNodeDepth)
                return "glTF node hierarchy deeper than " + std::to_string(kMaxGltfNodeDepth) + " levels";
            state[node] = 2;
            stack.pop_back();
        }
    }
    return {};
}

// The scenes' root nodes (every node when there is no scene list).
std::vector<std::size_t> root_nodes(const Json& doc, std::size_t node_count) {
    std::vector<std::size_t> roots;
    const auto scenes = doc.find("scenes");
    if (scenes != doc.end() && (scenes->is_array() || scenes->is_object()) && !scenes->empty()) {
        for (const auto& scene : *scenes) {
            const auto list = scene.is_object() ? scene.find("nodes") : scene.end();
            if (list == scene.end() || !list->is_array()) continue;
            for (const Json& r : *list)
                if (r.is_number_unsigned() && r.get<std::uint64_t>() < node_count) roots.push_back(r.get<std::size_t>());
        }
        return roots;
    }
    for (std::size_t i = 0; i < node_count; ++i) roots.push_back(i);
    return roots;
}

std::string node_problem(const Json& doc) {
    const std::vector<std::vector<std::size_t>> children = node_children(doc);
    std::vector<std::uint64_t> copies;
    if (std::string problem = node_graph_problem(children, copies); !problem.empty()) return problem;
    std::uint64_t total = 0;
    for (std::size_t r : root_nodes(doc, children.size())) total = std::min(total + copies[r], kMaxGltfNodeInstances + 1);
    if (total > kMaxGltfNodeInstances)
        return "glTF nodes shared by several parents expand to more than " + std::to_string(kMaxGltfNodeInstances) +
               " node copies";
    return {};
}

std::optional<std::uint64_t> unsigned_member(const Json& object, const char* key) {
    const auto it = object.find(key);
    if (it == object.end() || !it->is_number_unsigned()) return std::nullopt;
    return it->get<std::uint64_t>();
}

// %XX escapes of a URI decoded.
std::string decode_uri(const std::string& uri) {
    std::string out;
    for (std::size_t i = 0; i < uri.size(); ++i) {
        if (uri[i] == '%' && i + 2 < uri.size() && std::isxdigit(static_cast<unsigned char>(uri[i + 1])) &&
            std::isxdigit(static_cast<unsigned char>(uri[i + 2]))) {
            out += static_cast<char>(std::stoi(uri.substr(i + 1, 2), nullptr, 16));
            i += 2;
        } else {
            out += uri[i];
        }
    }
    return out;
}

// The bytes a buffer's data really has: a data URI's decoded length, a
// relative file's size, the GLB BIN chunk; none when unknown (Assimp or the
// file access decide: an absolute path, a missing file).
std::optional<std::uint64_t> buffer_data_bytes(const Json& buffer, std::size_t index, std::string_view bin,
                                               const std::filesystem::path& folder) {
    const auto uri = buffer.find("uri");
    if (uri == buffer.end()) return index == 0 ? std::optional<std::uint64_t>(bin.size()) : std::nullopt;
    if (!uri->is_string()) return std::nullopt;
    const std::string& text = uri->get_ref<const std::string&>();
    if (text.rfind("data:", 0) == 0) {
        const std::size_t comma = text.find(',');
        if (comma == std::string::npos || text.find(";base64", 0) > comma) return std::nullopt;
        const std::size_t chars = text.size() - comma - 1;
        return chars / 4 * 3 + (chars % 4 == 0 ? 0 : chars % 4 - 1);
    }
    const std::filesystem::path file(decode_uri(text));
    if (file.is_absolute() || text.find("://") != std::string::npos) return std::nullopt;
    std::error_code ec;
    const std::uintmax_t size = std::filesystem::file_size(folder / file, ec);
    if (ec) return std::nullopt;
    return size;
}

unsigned component_bytes(std::uint64_t type) {
    switch (type) {
        case 5120: case 5121: return 1;
        case 5122: case 5123: return 2;
        case 5125: case 5126: return 4;
        default: return 0;
    }
}

unsigned type_components(const std::string& type) {
    static const std::map<std::string, unsigned> counts{{"SCALAR", 1}, {"VEC2", 2}, {"VEC3", 3}, {"VEC4", 4},
                                                        {"MAT2", 4},   {"MAT3", 9}, {"MAT4", 16}};
    const auto it = counts.find(type);
    return it == counts.end() ? 0 : it->second;
}

// Declared lengths against the data: buffers against their bytes, buffer
// views against their buffers, accessors against their views.
struct DataBounds {
    const Json& doc;
    std::string_view bin;
    const std::filesystem::path& folder;
    std::vector<std::uint64_t> buffer_bytes, view_bytes;

    std::string buffers() {
        const auto list = doc.find("buffers");
        if (list == doc.end() || !list->is_array()) return {};
        for (std::size_t i = 0; i < list->size(); ++i) {
            const Json& b = (*list)[i];
            const std::uint64_t declared = b.is_object() ? unsigned_member(b, "byteLength").value_or(0) : 0;
            const std::optional<std::uint64_t> data = b.is_object() ? buffer_data_bytes(b, i, bin, folder) : std::nullopt;
            if (data && declared > *data)
                return "glTF buffer " + std::to_string(i) + " declares " + std::to_string(declared) +
                       " bytes, its data has " + std::to_string(*data);
            buffer_bytes.push_back(declared);
        }
        return {};
    }

    std::string views() {
        const auto list = doc.find("bufferViews");
        if (list == doc.end() || !list->is_array()) return {};
        for (std::size_t i = 0; i < list->size(); ++i) {
            const Json& v = (*list)[i];
            const std::uint64_t buffer = v.is_object() ? unsigned_member(v, "buffer").value_or(~0ull) : ~0ull;
            const std::uint64_t offset = v.is_object() ? unsigned_member(v, "byteOffset").value_or(0) : 0;
            const std::uint64_t length = v.is_object() ? unsigned_member(v, "byteLength").value_or(0) : 0;
            if (buffer < buffer_bytes.size() && (offset > buffer_bytes[buffer] || length > buffer_bytes[buffer] - offset))
                return "glTF bufferView " + std::to_string(i) + " (" + std::to_string(length) + " bytes at " +
                       std::to_string(offset) + ") lies outside its buffer of " + std::to_string(buffer_bytes[buffer]);
            view_bytes.push_back(buffer < buffer_bytes.size() ? length : ~0ull);
        }
        return {};
    }

    std::string accessor(const Json& a, std::size_t i, std::uint64_t& unbacked) const {
        const unsigned element = component_bytes(unsigned_member(a, "componentType").value_or(0)) *
                                 type_components(a.contains("type") && a["type"].is_string() ? a["type"].get<std::string>() : "");
        const std::uint64_t count = unsigned_member(a, "count").value_or(0);
        if (element == 0 || count == 0) return {};
        const long double bytes = static_cast<long double>(count) * element;
        const std::optional<std::uint64_t> view = unsigned_member(a, "bufferView");
        if (!view) {
            unbacked += static_cast<std::uint64_t>(std::min<long double>(bytes, 1e19L));
            if (unbacked > kMaxGltfUnbackedBytes)
                return "glTF accessors without a bufferView (zero-filled) need more than " +
                       std::to_string(kMaxGltfUnbackedBytes) + " bytes";
            return {};
        }
        if (*view >= view_bytes.size() || view_bytes[*view] == ~0ull) return {};
        const std::uint64_t offset = unsigned_member(a, "byteOffset").value_or(0);
        if (static_cast<long double>(offset) + bytes > static_cast<long double>(view_bytes[*view]))
            return "glTF accessor " + std::to_string(i) + " (" + std::to_string(count) + " elements of " +
                   std::to_string(element) + " bytes at " + std::to_string(offset) + ") does not fit in its bufferView of " +
                   std::to_string(view_bytes[*view]) + " bytes";
        return {};
    }

    std::string accessors() const {
        const auto list = doc.find("accessors");
        if (list == doc.end() || !list->is_array()) return {};
        std::uint64_t unbacked = 0;
        for (std::size_t i = 0; i < list->size(); ++i)
            if ((*list)[i].is_object())
                if (std::string problem = accessor((*list)[i], i, unbacked); !problem.empty()) return problem;
        return {};
    }
};

// KHR_texture_transform's offset and scale are read as two numbers each,
// unchecked; anywhere in the document.
std::string texture_transform_problem(const Json& doc) {
    std::vector<const Json*> stack{&doc};
    while (!stack.empty()) {
        const Json& v = *stack.back();
        stack.pop_back();
        if (v.is_object()) {
            const auto t = v.find("KHR_texture_transform");
            if (t != v.end() && t->is_object())
                for (const char* key : {"offset", "scale"}) {
                    const auto a = t->find(key);
                    if (a == t->end()) continue;
                    if (!a->is_array() || a->size() != 2 || !(*a)[0].is_number() || !(*a)[1].is_number())
                        return std::string("KHR_texture_transform.") + key + " must be an array of 2 numbers";
                }
        }
        if (v.is_structured())
            for (const Json& child : v) stack.push_back(&child);
    }
    return {};
}

}  // namespace

std::string gltf_bounds_problem(std::string_view file, bool binary, const std::filesystem::path& folder) {
    std::string_view json = file, bin;
    if (binary) {
        GlbParts parts = split_glb(file);
        if (!parts.problem.empty()) return parts.problem;
        json = parts.json;
        bin = parts.bin;
    }
    if (const std::size_t at = json_depth_exceeded_at(json, kMaxGltfJsonDepth))
        return "glTF JSON nested deeper than " + std::to_string(kMaxGltfJsonDepth) + " levels (at byte " +
               std::to_string(at) + ")";
    // Text nlohmann does not take (Assimp's parser is more lenient: invalid
    // UTF-8 in a name) is left to Assimp: its depth is bounded already.
    const Json doc = Json::parse(json.begin(), json.end(), nullptr, false);
    if (doc.is_discarded() || !doc.is_object()) return {};
    if (std::string problem = node_problem(doc); !problem.empty()) return problem;
    if (std::string problem = texture_transform_problem(doc); !problem.empty()) return problem;
    DataBounds data{doc, bin, folder, {}, {}};
    if (std::string problem = data.buffers(); !problem.empty()) return problem;
    if (std::string problem = data.views(); !problem.empty()) return problem;
    return data.accessors();
}

}  // namespace kdrt::detail
