#include "report.h"

#include "machine_info.h"

#include <kdrt/error.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace kdrt::bench {

namespace {

std::string g_invocation;

std::string csv_field(const std::string& s) {
    if (s.find_first_of(",\"\n") == std::string::npos) return s;
    std::string q = "\"";
    for (char c : s) {
        if (c == '"') q += '"';
        q += c;
    }
    return q + "\"";
}

std::string md_cell(const std::string& s) {
    std::string r;
    for (char c : s) {
        if (c == '|') r += "\\|";
        else if (c == '\n') r += ' ';
        else r += c;
    }
    return r;
}

}  // namespace

std::string TextTable::markdown() const {
    std::ostringstream o;
    o << "|";
    for (const std::string& h : header) o << " " << md_cell(h) << " |";
    o << "\n|";
    for (std::size_t i = 0; i < header.size(); ++i) o << (i == 0 ? "---|" : "---:|");
    o << "\n";
    for (const auto& row : rows) {
        o << "|";
        for (std::size_t i = 0; i < header.size(); ++i) o << " " << (i < row.size() ? md_cell(row[i]) : "") << " |";
        o << "\n";
    }
    return o.str();
}

std::string TextTable::csv() const {
    std::ostringstream o;
    auto line = [&](const std::vector<std::string>& v) {
        for (std::size_t i = 0; i < v.size(); ++i) o << (i ? "," : "") << csv_field(v[i]);
        o << "\n";
    };
    line(header);
    for (const auto& row : rows) line(row);
    return o.str();
}

std::string fmt(double v, int decimals) {
    if (std::isnan(v)) return "-";
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
    return buf;
}

std::string fmt_ms(double ms) {
    if (std::isnan(ms)) return "-";
    const double a = std::abs(ms);
    return fmt(ms, a < 1.0 ? 3 : a < 10.0 ? 2 : a < 1000.0 ? 1 : 0);
}

std::string fmt_ratio(double r) {
    if (std::isnan(r) || std::isinf(r)) return "-";
    return fmt(r, r < 10.0 ? 2 : 1) + "x";
}

void set_invocation(int argc, char** argv) {
    g_invocation.clear();
    for (int i = 0; i < argc; ++i) {
        std::string a = argv[i];
        if (i == 0) {
            const auto slash = a.find_last_of('/');
            if (slash != std::string::npos) a = a.substr(slash + 1);
        }
        if (a.find_first_of(" \t'\"") != std::string::npos) a = "'" + a + "'";
        g_invocation += (i ? " " : "") + a;
    }
}

const std::string& invocation() { return g_invocation; }

std::string markdown_preamble(const std::string& title) {
    std::ostringstream o;
    o << "# " << title << "\n\n";
    for (const std::string& l : machine_lines()) o << "- " << l << "\n";
    o << "- command: `" << invocation() << "`\n\n";
    return o.str();
}

std::string csv_preamble(const std::string& title) {
    std::ostringstream o;
    o << "# " << title << "\n";
    for (const std::string& l : machine_lines()) o << "# " << l << "\n";
    o << "# command: " << invocation() << "\n";
    return o.str();
}

void write_text_file(const std::filesystem::path& path, const std::string& text) {
    std::error_code ec;
    if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path(), ec);
    std::ofstream out(path, std::ios::binary);
    out << text;
    if (!out) throw Error(ErrorCode::Io, path.string() + ": cannot write");
}

void write_report(const std::filesystem::path& out, const std::string& name, const std::string& command,
                  const std::string& markdown, const TextTable& csv) {
    const std::filesystem::path md_path = out / (name + ".md"), csv_path = out / (name + ".csv");
    write_text_file(md_path, markdown);
    write_text_file(csv_path, csv_preamble("kdrt-bench " + command) + csv.csv());
    std::fprintf(stderr, "kdrt-bench %s: wrote %s and %s\n", command.c_str(), md_path.c_str(), csv_path.c_str());
}

}  // namespace kdrt::bench
