#include "scene/import_process.h"

#include "common/printable_text.h"
#include "scene/model_wire.h"

#include <kdrt/error.h>

#include <dlfcn.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

extern char** environ;

namespace kdrt::detail {
namespace {

namespace fs = std::filesystem;

constexpr const char* kHelperName = "kdrt-import";
constexpr std::size_t kStderrTail = 2048;  // bytes of the helper's stderr kept for a message
constexpr int kPollMs = 100;               // how often keep_going and the clock are looked at

bool inside(const fs::path& file, const fs::path& dir) {
    const auto [d, f] = std::mismatch(dir.begin(), dir.end(), file.begin(), file.end());
    return d == dir.end();
}

std::vector<fs::path> helper_candidates() {
    if (const char* env = std::getenv("KDRT_IMPORT_HELPER"); env && *env) return {fs::path(env)};
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    fs::path self;  // libkdrt.so, or the program libkdrt is linked into
    Dl_info info{};
    if (dladdr(reinterpret_cast<void*>(&helper_candidates), &info) && info.dli_fname && *info.dli_fname)
        self = fs::weakly_canonical(fs::absolute(info.dli_fname, ec), ec);
    if (self.empty()) self = exe;
    std::vector<fs::path> list;
#ifdef KDRT_IMPORT_HELPER_BUILD_PATH
    const fs::path build_dir = KDRT_BUILD_DIR;
    if ((!self.empty() && inside(self, build_dir)) || (!exe.empty() && inside(exe, build_dir)))
        list.emplace_back(KDRT_IMPORT_HELPER_BUILD_PATH);
#endif
#ifdef KDRT_INSTALL_FULL_LIBEXECDIR
    if (!self.empty()) list.push_back((self.parent_path() / KDRT_LIBDIR_TO_LIBEXECDIR / kHelperName).lexically_normal());
    if (!exe.empty()) list.push_back((exe.parent_path() / KDRT_BINDIR_TO_LIBEXECDIR / kHelperName).lexically_normal());
    list.push_back(fs::path(KDRT_INSTALL_FULL_LIBEXECDIR) / kHelperName);
#endif
    return list;
}

fs::path find_helper(const fs::path& model) {
    std::string looked;
    for (const fs::path& file : helper_candidates()) {
        if (::access(file.c_str(), X_OK) == 0) return file;
        looked += (looked.empty() ? "" : ", ") + file.string();
    }
    throw Error(ErrorCode::Unsupported,
                model.string() + ": cannot import in a child process: the helper " + kHelperName +
                    " is not installed (looked for " + looked + "; KDRT_IMPORT_HELPER may name it; "
                    "ImportOptions::isolation = InProcess imports in this process)");
}

std::vector<std::string> helper_arguments(const fs::path& helper, const fs::path& model,
                                          const std::array<double, 16>& transform, const ImportOptions& options) {
    std::vector<std::string> args{helper.string(), "--parent", std::to_string(::getpid()), "--memory-limit",
                                  std::to_string(options.memory_limit ? options.memory_limit : default_import_memory_limit())};
    if (options.time_limit_s > 0.0)
        args.insert(args.end(), {"--cpu-seconds", std::to_string(static_cast<long long>(options.time_limit_s) + 2)});
    if (options.allow_outside_files) args.emplace_back("--allow-outside-files");
    args.emplace_back("--transform");
    for (double v : transform) {
        char text[40];
        std::snprintf(text, sizeof text, "%a", v);  // exact
        args.emplace_back(text);
    }
    args.insert(args.end(), {"--", model.string()});
    return args;
}

// The helper, running: killed and reaped if still there when this goes.
class Helper {
public:
    Helper(const std::vector<std::string>& args, const fs::path& model) {
        int out[2], err[2];
        if (::pipe2(out, O_CLOEXEC) != 0) fail_start(model, errno);
        if (::pipe2(err, O_CLOEXEC) != 0) {
            const int e = errno;
            ::close(out[0]);
            ::close(out[1]);
            fail_start(model, e);
        }
        out_ = out[0];
        err_ = err[0];
        posix_spawn_file_actions_t actions;
        posix_spawn_file_actions_init(&actions);
        posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
        posix_spawn_file_actions_adddup2(&actions, out[1], 1);
        posix_spawn_file_actions_adddup2(&actions, err[1], 2);
        posix_spawn_file_actions_addclosefrom_np(&actions, 3);
        posix_spawnattr_t attr;
        posix_spawnattr_init(&attr);
        sigset_t none, all;
        sigemptyset(&none);
        sigfillset(&all);
        posix_spawnattr_setsigmask(&attr, &none);
        posix_spawnattr_setsigdefault(&attr, &all);
        posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);
        std::vector<char*> argv;
        for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
        argv.push_back(nullptr);
        const int rc = ::posix_spawn(&pid_, argv[0], &actions, &attr, argv.data(), environ);
        posix_spawn_file_actions_destroy(&actions);
        posix_spawnattr_destroy(&attr);
        ::close(out[1]);
        ::close(err[1]);
        if (rc != 0) {
            pid_ = -1;
            close_pipes();
            fail_start(model, rc);
        }
    }
    ~Helper() {
        stop();
        close_pipes();
    }
    Helper(const Helper&) = delete;
    Helper& operator=(const Helper&) = delete;

    int out() const { return out_; }
    int err() const { return err_; }
    void close_out() { close_fd(out_); }
    void close_err() { close_fd(err_); }
    // Kills it (if still running) and waits for it.
    void stop() {
        if (pid_ <= 0) return;
        ::kill(pid_, SIGKILL);
        wait();
    }
    // Its wait status, once it has ended (blocking); -1 when it cannot be had.
    int wait() {
        if (pid_ <= 0) return status_;
        int status = 0;
        while (::waitpid(pid_, &status, 0) < 0)
            if (errno != EINTR) {
                status = -1;  // ECHILD: SIGCHLD ignored by the program, the status is gone
                break;
            }
        pid_ = -1;
        status_ = status;
        return status_;
    }

private:
    [[noreturn]] static void fail_start(const fs::path& model, int error) {
        throw Error(ErrorCode::Io, model.string() + ": cannot start the import helper: " + std::strerror(error));
    }
    static void close_fd(int& fd) {
        if (fd >= 0) ::close(fd);
        fd = -1;
    }
    void close_pipes() {
        close_fd(out_);
        close_fd(err_);
    }
    pid_t pid_ = -1;
    int out_ = -1, err_ = -1, status_ = -1;
};

// Appends what is there to read; false at the end of the stream.
bool drain(int fd, std::vector<std::uint8_t>& into, std::size_t keep_last) {
    std::uint8_t chunk[65536];
    const ssize_t n = ::read(fd, chunk, sizeof chunk);
    if (n < 0) return errno == EINTR || errno == EAGAIN;
    if (n == 0) return false;
    into.insert(into.end(), chunk, chunk + n);
    if (keep_last && into.size() > keep_last) into.erase(into.begin(), into.end() - static_cast<std::ptrdiff_t>(keep_last));
    return true;
}

struct Collected {
    std::vector<std::uint8_t> result, stderr_tail;
};

// Reads the helper's output until both pipes close, polling keep_going and
// the wall clock in between.
Collected collect(Helper& helper, const fs::path& model, const ImportOptions& options) {
    const std::uint64_t memory_limit = options.memory_limit ? options.memory_limit : default_import_memory_limit();
    using Clock = std::chrono::steady_clock;
    const auto deadline = Clock::now() + std::chrono::duration<double>(options.time_limit_s);
    Collected c;
    while (helper.out() >= 0 || helper.err() >= 0) {
        pollfd fds[2] = {{helper.out(), POLLIN, 0}, {helper.err(), POLLIN, 0}};
        const int ready = ::poll(fds, 2, kPollMs);
        if (ready < 0 && errno != EINTR)
            throw Error(ErrorCode::Io, model.string() + ": waiting for the import helper: " + std::strerror(errno));
        if (options.keep_going && !options.keep_going()) {
            helper.stop();
            throw Error(ErrorCode::Cancelled, model.string() + ": import cancelled");
        }
        if (options.time_limit_s > 0.0 && Clock::now() > deadline) {
            helper.stop();
            throw Error(ErrorCode::ResourceLimit, model.string() + ": the import took longer than " +
                                                      std::to_string(static_cast<long long>(options.time_limit_s)) +
                                                      " s (ImportOptions::time_limit_s) and was stopped");
        }
        if (ready <= 0) continue;
        if (fds[0].revents && !drain(helper.out(), c.result, 0)) helper.close_out();
        if (c.result.size() > memory_limit) {  // more than the helper could hold: not a result
            helper.stop();
            throw Error(ErrorCode::InvalidScene, model.string() + ": the import helper sent more than its memory limit");
        }
        if (fds[1].revents && !drain(helper.err(), c.stderr_tail, kStderrTail)) helper.close_err();
    }
    return c;
}

// The last line the helper printed, printable, or empty.
std::string last_line(const std::vector<std::uint8_t>& text) {
    std::string s(text.begin(), text.end());
    while (!s.empty() && (s.back() == '\n' || s.back() == '\r')) s.pop_back();
    const std::size_t nl = s.rfind('\n');
    return printable(nl == std::string::npos ? s : s.substr(nl + 1), 300);
}

[[noreturn]] void fail_from_status(int status, const Collected& c, const fs::path& model, const ImportOptions& options) {
    const std::string file = model.string() + ": ";
    const std::string said = last_line(c.stderr_tail);
    if (status >= 0 && WIFSIGNALED(status)) {
        const int sig = WTERMSIG(status);
        const char* name = sigabbrev_np(sig);
        const std::string signal = std::string("SIG") + (name ? name : std::to_string(sig).c_str());
        if (sig == SIGXCPU)
            throw Error(ErrorCode::ResourceLimit, file + "the import used more than its " +
                                                      std::to_string(static_cast<long long>(options.time_limit_s)) +
                                                      " s of CPU time (ImportOptions::time_limit_s) and was stopped");
        if (sig == SIGKILL)
            throw Error(ErrorCode::ResourceLimit, file + "the import helper was killed (SIGKILL: out of memory?)");
        throw Error(ErrorCode::InvalidScene,
                    file + "the importer (Assimp) " + (sig == SIGABRT ? "aborted" : "crashed") + " on this file (" +
                        signal + (sig == SIGSEGV ? ": a stack overflow or a bad memory access" : "") + ")" +
                        (said.empty() ? "" : ": " + said));
    }
    const std::string exit = status >= 0 && WIFEXITED(status) ? "exit status " + std::to_string(WEXITSTATUS(status))
                                                              : std::string("its exit status is unknown");
    throw Error(ErrorCode::InvalidScene,
                file + "the import helper ended without a result (" + exit + ")" + (said.empty() ? "" : ": " + said));
}

}  // namespace

std::uint64_t default_import_memory_limit() {
    const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
    const std::uint64_t half = pages > 0 && page > 0 ? static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page) / 2
                                                     : std::uint64_t{4} << 30;
    return std::min<std::uint64_t>(half, std::uint64_t{16} << 30);
}

ImportedModel import_in_child_process(const fs::path& path, const std::array<double, 16>& transform,
                                      const ImportOptions& options) {
    const fs::path helper_file = find_helper(path);
    Helper helper(helper_arguments(helper_file, path, transform, options), path);
    const Collected c = collect(helper, path, options);
    const int status = helper.wait();
    // A whole result counts whatever came after it (a crash in Assimp's clean-up, a leak
    // report, a status lost to an ignored SIGCHLD); a clean exit without one is damage.
    const bool clean_exit = status >= 0 && WIFEXITED(status) && WEXITSTATUS(status) == 0;
    if (clean_exit || is_complete_import_result(c.result.data(), c.result.size()))
        return decode_import_result(c.result.data(), c.result.size(), path.string());
    fail_from_status(status, c, path, options);
}

}  // namespace kdrt::detail
