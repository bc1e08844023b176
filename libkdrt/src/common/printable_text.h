// Text from an input file quoted in an error message (a material name, a JSON
// key, an OBJ line): control characters escaped so that nothing from the file
// can move the cursor or recolour the terminal, and the length bounded so that
// a huge token does not become a huge message.
#pragma once

#include <algorithm>
#include <cstddef>
#include <string>
#include <string_view>

namespace kdrt::detail {

inline constexpr std::size_t kMaxQuotedChars = 80;

// `text` with C0 controls and DEL as \n, \t, \r or \xHH and a backslash as
// "\\"; cut to about max_chars (at a UTF-8 character boundary) with "..." appended.
inline std::string printable(std::string_view text, std::size_t max_chars = kMaxQuotedChars) {
    static constexpr char kHex[] = "0123456789abcdef";
    std::string out;
    out.reserve(std::min(text.size(), max_chars) + 8);
    for (std::size_t i = 0; i < text.size(); ++i) {
        if (out.size() >= max_chars) {
            // Never leave half of a multi-byte UTF-8 character behind.
            while (!out.empty() && (static_cast<unsigned char>(out.back()) & 0xC0) == 0x80) out.pop_back();
            if (!out.empty() && (static_cast<unsigned char>(out.back()) & 0xC0) == 0xC0) out.pop_back();
            out += "...";
            break;
        }
        const auto c = static_cast<unsigned char>(text[i]);
        switch (c) {
            case '\n': out += "\\n"; break;
            case '\t': out += "\\t"; break;
            case '\r': out += "\\r"; break;
            case '\\': out += "\\\\"; break;
            default:
                if (c < 0x20 || c == 0x7F) {
                    out += "\\x";
                    out += kHex[c >> 4];
                    out += kHex[c & 15];
                } else {
                    out += static_cast<char>(c);
                }
        }
    }
    return out;
}

}  // namespace kdrt::detail
