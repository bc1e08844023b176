#include "subprocess.h"

#include "stats.h"

#include <kdrt/error.h>

#include <fcntl.h>
#include <poll.h>
#include <pty.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <map>

extern char** environ;

namespace kdrt::bench {

std::filesystem::path find_program(const std::string& name) {
    if (name.find('/') != std::string::npos) {
        std::error_code ec;
        return std::filesystem::is_regular_file(name, ec) ? std::filesystem::absolute(name) : std::filesystem::path();
    }
    const char* path = std::getenv("PATH");
    std::string dirs = path ? path : "/usr/local/bin:/usr/bin:/bin";
    std::size_t start = 0;
    while (start <= dirs.size()) {
        const std::size_t colon = dirs.find(':', start);
        const std::string dir = dirs.substr(start, colon == std::string::npos ? std::string::npos : colon - start);
        if (!dir.empty()) {
            const std::filesystem::path p = std::filesystem::path(dir) / name;
            if (access(p.c_str(), X_OK) == 0) return p;
        }
        if (colon == std::string::npos) break;
        start = colon + 1;
    }
    return {};
}

std::filesystem::path self_executable() {
    std::error_code ec;
    auto p = std::filesystem::read_symlink("/proc/self/exe", ec);
    return ec ? std::filesystem::path() : p;
}

ChildResult run_child(const ChildOptions& options) {
    if (options.argv.empty()) throw Error(ErrorCode::InvalidArgument, "run_child: empty argv");
    const std::filesystem::path program = find_program(options.argv[0]);
    if (program.empty()) throw Error(ErrorCode::Io, options.argv[0] + ": program not found");

    // Everything the child needs is prepared before fork(): after it, only
    // async-signal-safe calls (the parent may have threads).
    std::map<std::string, std::string> env;
    for (char** e = environ; *e; ++e) {
        const char* eq = std::strchr(*e, '=');
        if (eq) env[std::string(*e, static_cast<std::size_t>(eq - *e))] = eq + 1;
    }
    for (const auto& [k, v] : options.env) env[k] = v;
    std::vector<std::string> env_strings;
    for (const auto& [k, v] : env) env_strings.push_back(k + "=" + v);
    std::vector<char*> envp, argv;
    for (std::string& s : env_strings) envp.push_back(s.data());
    envp.push_back(nullptr);
    std::vector<std::string> args = options.argv;
    for (std::string& s : args) argv.push_back(s.data());
    argv.push_back(nullptr);
    const std::string cwd = options.cwd.string();

    int master = -1, slave = -1;
    if (options.capture_stdout) {
        termios raw{};
        cfmakeraw(&raw);
        if (openpty(&master, &slave, nullptr, &raw, nullptr) != 0)
            throw Error(ErrorCode::Io, std::string("openpty: ") + std::strerror(errno));
    }
    const int devnull = open("/dev/null", O_RDWR);

    ChildResult r;
    const Stopwatch clock;
    const pid_t pid = fork();
    if (pid < 0) throw Error(ErrorCode::Io, std::string("fork: ") + std::strerror(errno));
    if (pid == 0) {
        dup2(devnull, STDIN_FILENO);
        dup2(options.capture_stdout ? slave : devnull, STDOUT_FILENO);
        if (options.merge_stderr) dup2(STDOUT_FILENO, STDERR_FILENO);
        else if (!options.show_stderr) dup2(devnull, STDERR_FILENO);
        if (master >= 0) close(master);
        if (slave >= 0) close(slave);
        close(devnull);
        if (!cwd.empty() && chdir(cwd.c_str()) != 0) _exit(126);
        execve(program.c_str(), argv.data(), envp.data());
        _exit(127);
    }
    close(devnull);
    if (slave >= 0) close(slave);

    bool killed = false;
    if (master >= 0) {
        char buf[4096];
        for (;;) {
            pollfd pfd{master, POLLIN, 0};
            int wait_ms = -1;
            if (options.timeout_s > 0.0) {
                const double left = options.timeout_s * 1000.0 - clock.ms();
                if (left <= 0.0) {
                    kill(pid, SIGKILL);
                    killed = true;
                    break;
                }
                wait_ms = static_cast<int>(left) + 1;
            }
            const int pr = poll(&pfd, 1, wait_ms);
            if (pr < 0 && errno == EINTR) continue;
            if (pr == 0) continue;  // timeout: checked above
            const ssize_t n = read(master, buf, sizeof buf);
            if (n <= 0) break;  // EIO once the child and its descendants closed the terminal
            for (ssize_t i = 0; i < n; ++i) {
                if (buf[i] == '\r') continue;
                r.out += buf[i];
                if (buf[i] == '\n' && r.first_line_ms < 0) r.first_line_ms = clock.ms();
            }
        }
        close(master);
    }
    int status = 0;
    rusage ru{};
    if (master < 0 && options.timeout_s > 0.0) {
        for (;;) {
            const pid_t w = wait4(pid, &status, WNOHANG, &ru);
            if (w == pid || (w < 0 && errno != EINTR)) break;
            if (!killed && clock.ms() > options.timeout_s * 1000.0) {
                kill(pid, SIGKILL);
                killed = true;
            }
            usleep(1000);
        }
    } else {
        while (wait4(pid, &status, 0, &ru) < 0 && errno == EINTR) {
        }
    }
    r.wall_ms = clock.ms();
    r.timed_out = killed;
    r.max_rss_kib = ru.ru_maxrss;
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : WIFSIGNALED(status) ? 128 + WTERMSIG(status) : -1;
    return r;
}

TempDir::TempDir(const std::string& prefix) {
    std::string tmpl = (std::filesystem::temp_directory_path() / (prefix + "-XXXXXX")).string();
    if (!mkdtemp(tmpl.data())) throw Error(ErrorCode::Io, "cannot create a temporary directory in " + tmpl);
    path_ = tmpl;
}

TempDir::~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
}

std::filesystem::path TempDir::fresh(const std::string& name) {
    const std::filesystem::path p = path_ / (name + "-" + std::to_string(counter_++));
    std::filesystem::create_directories(p);
    return p;
}

}  // namespace kdrt::bench
