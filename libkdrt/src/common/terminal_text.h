// Text from outside the program (environment variables, driver strings, file
// contents) made safe to print on a terminal: control characters, which could
// move the cursor, retitle the window or fake other output, become visible
// escapes.
#pragma once

#include <cstdio>
#include <string>
#include <string_view>

namespace kdrt::detail {

// C0 controls and DEL as \n, \t, \r, \e or \xNN; UTF-8-encoded C1 controls
// (U+0080..U+009F, which some terminals obey) as \u00NN. Everything else,
// including other UTF-8, is kept; so are line breaks with keep_newlines
// (multi-line messages such as build logs).
inline std::string escape_for_terminal(std::string_view text, bool keep_newlines = false) {
    std::string out;
    out.reserve(text.size());
    char buf[8];
    for (std::size_t i = 0; i < text.size(); ++i) {
        const auto c = static_cast<unsigned char>(text[i]);
        if (c == '\n') out += keep_newlines ? "\n" : "\\n";
        else if (c == '\t') out += "\\t";
        else if (c == '\r') out += "\\r";
        else if (c == 0x1b) out += "\\e";
        else if (c < 0x20 || c == 0x7f) {
            std::snprintf(buf, sizeof buf, "\\x%02x", c);
            out += buf;
        } else if (c == 0xc2 && i + 1 < text.size() && static_cast<unsigned char>(text[i + 1]) >= 0x80 &&
                   static_cast<unsigned char>(text[i + 1]) <= 0x9f) {
            std::snprintf(buf, sizeof buf, "\\u%04x", static_cast<unsigned char>(text[++i]));
            out += buf;
        } else {
            out += static_cast<char>(c);
        }
    }
    return out;
}

}  // namespace kdrt::detail
