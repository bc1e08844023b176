#include "opencl/embedded_cl.h"

#include <algorithm>
#include <string_view>
#include <vector>

namespace kdrt::detail::ocl {

namespace {

bool is_blank(char c) { return c == ' ' || c == '\t'; }

// The file name of the path a line includes (`#include "a/b.h"`,
// `# include <b.h>`: "b.h"), or empty for any other line.
std::string_view included_file_name(std::string_view line) {
    std::size_t i = 0;
    auto skip_blanks = [&] {
        while (i < line.size() && is_blank(line[i])) ++i;
    };
    skip_blanks();
    if (i >= line.size() || line[i] != '#') return {};
    ++i;
    skip_blanks();
    constexpr std::string_view kInclude = "include";
    if (line.substr(i, kInclude.size()) != kInclude) return {};
    i += kInclude.size();
    skip_blanks();
    if (i >= line.size() || (line[i] != '"' && line[i] != '<')) return {};
    const char close = line[i] == '"' ? '"' : '>';
    const std::size_t end = line.find(close, i + 1);
    if (end == std::string_view::npos) return {};
    const std::string_view path = line.substr(i + 1, end - i - 1);
    const std::size_t slash = path.rfind('/');
    return slash == std::string_view::npos ? path : path.substr(slash + 1);
}

// The file names of the embedded headers (".h"): what included_file_name
// must not name for a line to be kept.
std::vector<std::string_view> header_names(std::span<const EmbeddedClFile> files) {
    std::vector<std::string_view> names;
    for (const EmbeddedClFile& file : files) {
        const std::string_view name = file.name;
        const std::size_t slash = name.rfind('/');
        const std::string_view base = slash == std::string_view::npos ? name : name.substr(slash + 1);
        if (base.size() > 2 && base.substr(base.size() - 2) == ".h") names.push_back(base);
    }
    return names;
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
    const std::vector<std::string_view> headers = header_names(files);
    const auto includes_embedded_header = [&](std::string_view line) {
        const std::string_view included = included_file_name(line);
        return !included.empty() && std::find(headers.begin(), headers.end(), included) != headers.end();
    };
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
            if (!includes_embedded_header(content)) source += line;
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
