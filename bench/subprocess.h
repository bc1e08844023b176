// Running a child process and measuring it: wall time from just before
// fork() to reaping, when its first stdout line arrived, and its peak
// resident memory (wait4's ru_maxrss). Stdout is read through a
// pseudo-terminal, so the child's stdio flushes at each newline and a line's
// arrival time is when it was printed, not when the process exited.
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace kdrt::bench {

struct ChildOptions {
    std::vector<std::string> argv;                           // argv[0]: a path, or a name looked up in $PATH
    std::vector<std::pair<std::string, std::string>> env;    // added to (or replacing in) our environment
    std::filesystem::path cwd;                               // empty: ours
    bool capture_stdout = true;                              // else stdout goes to /dev/null
    bool show_stderr = false;                                // else stderr goes to /dev/null
    bool merge_stderr = false;                               // stderr joins the captured stdout
    double timeout_s = 0.0;                                  // > 0: SIGKILL after this long
};

struct ChildResult {
    int exit_code = -1;          // the exit status, or 128 + signal
    bool timed_out = false;
    double wall_ms = 0.0;        // fork to reaped
    double first_line_ms = -1;   // fork to the first complete stdout line; -1 if none
    std::string out;             // stdout, '\r' removed
    long max_rss_kib = 0;        // the child's peak resident set
};

ChildResult run_child(const ChildOptions& options);

// The absolute path of a program: as given when it contains '/', else from $PATH; empty if not found.
std::filesystem::path find_program(const std::string& name);

// This executable's path (/proc/self/exe).
std::filesystem::path self_executable();

// A fresh empty directory under the system temp dir, removed by the destructor.
class TempDir {
public:
    explicit TempDir(const std::string& prefix = "kdrt-bench");
    ~TempDir();
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;
    const std::filesystem::path& path() const { return path_; }
    // A new empty subdirectory (name + counter).
    std::filesystem::path fresh(const std::string& name);

private:
    std::filesystem::path path_;
    int counter_ = 0;
};

}  // namespace kdrt::bench
