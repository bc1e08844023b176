// Where JSON text nests too deep, found by a linear scan before or after a
// parser refuses it: scene files (scene_loader.cpp) and glTF files
// (gltf_bounds_check.cpp).
#pragma once

#include <cstddef>
#include <string_view>

namespace kdrt::detail {

// 1-based position of the first bracket nested deeper than `depth` in JSON
// text (strings skipped), or 0 when there is none.
inline std::size_t json_depth_exceeded_at(std::string_view text, std::size_t depth) {
    std::size_t level = 0;
    bool in_string = false;
    for (std::size_t i = 0; i < text.size(); ++i) {
        const char c = text[i];
        if (in_string) {
            if (c == '\\') ++i;
            else if (c == '"') in_string = false;
        } else if (c == '"') {
            in_string = true;
        } else if (c == '{' || c == '[') {
            if (++level > depth) return i + 1;
        } else if ((c == '}' || c == ']') && level > 0) {
            --level;
        }
    }
    return 0;
}

}  // namespace kdrt::detail
