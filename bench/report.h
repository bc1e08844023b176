// Writing results: plain tables rendered as Markdown and CSV, each output
// headed by the machine, the date and the exact command that produced it.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace kdrt::bench {

struct TextTable {
    std::vector<std::string> header;
    std::vector<std::vector<std::string>> rows;

    void add(std::vector<std::string> row) { rows.push_back(std::move(row)); }
    std::string markdown() const;
    std::string csv() const;
};

// Numbers for tables: "-" for NaN; fixed decimals.
std::string fmt(double v, int decimals = 1);
// Milliseconds with a precision that suits the magnitude (0.123, 12.3, 1234).
std::string fmt_ms(double ms);
// A ratio such as "1.83x".
std::string fmt_ratio(double r);

// The command line as typed (set once by main).
void set_invocation(int argc, char** argv);
const std::string& invocation();

// "# title" followed by the machine lines and the command, as Markdown.
std::string markdown_preamble(const std::string& title);
// The same as CSV comment lines ("# ...").
std::string csv_preamble(const std::string& title);

// Writes a file, creating its directory; throws kdrt::Error(Io) on failure.
void write_text_file(const std::filesystem::path& path, const std::string& text);

// A command's two outputs: out/NAME.md (the Markdown as given) and out/NAME.csv
// (the table under csv_preamble("kdrt-bench COMMAND")), then says so on stderr.
void write_report(const std::filesystem::path& out, const std::string& name, const std::string& command,
                  const std::string& markdown, const TextTable& csv);

}  // namespace kdrt::bench
