#include "opencl/embedded_cl.h"

#include <string_view>

namespace kdrt::detail::ocl {

namespace {

bool is_blank(char c) { return c == ' ' || c == '\t'; }

// True for `#include "kdrt_shared.h"`, `# include <kdrt/shared/kdrt_shared.h>`,
// `#include "../libkdrt/include/kdrt/shared/kdrt_shared.h"` and the like.
bool includes_shared_header(std::string_view line) {
    std::size_t i = 0;
    auto skip_blanks = [&] {
        while (i < line.size() && is_blank(line[i])) ++i;
    };
    skip_blanks();
    if (i >= line.size() || line[i] != '#') return false;
    ++i;
    skip_blanks();
    constexpr std::string_view kInclude = "include";
    if (line.substr(i, kInclude.size()) != kInclude) return false;
    i += kInclude.size();
    skip_blanks();
    if (i >= line.size() || (line[i] != '"' && line[i] != '<')) return false;
    const char close = line[i] == '"' ? '"' : '>';
    const std::size_t end = line.find(close, i + 1);
    if (end == std::string_view::npos) return false;
    const std::string_view path = line.substr(i + 1, end - i - 1);
    constexpr std::string_view kHeader = "kdrt_shared.h";
    if (path.size() < kHeader.size() || path.substr(path.size() - kHeader.size()) != kHeader) return false;
    return path.size() == kHeader.size() || path[path.size() - kHeader.size() - 1] == '/';
}

std::string quoted(std::string_view name) {
    std::string out = "\"";
    for (char c : name) {
        if (c == '"' || c == '\\') out += '\\';
        out += c;
    }
    return out + "\"";
}

}  // namespace

std::string assemble_kernel_source(std::span<const EmbeddedClFile> files) {
    std::string source;
    for (const EmbeddedClFile& file : files) {
        source += "#line 1 " + quoted(file.name) + "\n";
        std::string_view text = file.text;
        while (!text.empty()) {
            const std::size_t newline = text.find('\n');
            const std::size_t length = newline == std::string_view::npos ? text.size() : newline;
            std::string_view line = text.substr(0, length);
            std::string_view content = line;
            if (!content.empty() && content.back() == '\r') content.remove_suffix(1);
            if (!includes_shared_header(content)) source += line;
            source += '\n';
            text.remove_prefix(newline == std::string_view::npos ? text.size() : newline + 1);
        }
    }
    return source;
}

std::string assemble_kernel_source() {
    return assemble_kernel_source(std::span<const EmbeddedClFile>(kEmbeddedClFiles, kEmbeddedClFileCount));
}

}  // namespace kdrt::detail::ocl
