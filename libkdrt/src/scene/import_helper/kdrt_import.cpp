// kdrt-import: the helper process of ImportIsolation::ChildProcess
// (src/scene/import_process.h). Not a program for users: libkdrt starts it as
//   kdrt-import --parent PID --memory-limit BYTES [--cpu-seconds S]
//               [--allow-outside-files] --transform 16 x %a -- MODEL
// It limits itself (address space, CPU time, no core file), dies with its
// parent, imports MODEL in this process and writes the result
// (src/scene/model_wire.h) to its standard output. Whatever the import
// throws becomes an error record; a crash is seen by the parent.
#include "scene/model_wire.h"

#include <kdrt/error.h>
#include <kdrt/model_import.h>

#include <sys/prctl.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <new>
#include <string>
#include <vector>

namespace {

#if defined(__SANITIZE_ADDRESS__)
constexpr bool kAddressSanitizer = true;  // its shadow memory needs terabytes of address space
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kAddressSanitizer = true;
#else
constexpr bool kAddressSanitizer = false;
#endif
#else
constexpr bool kAddressSanitizer = false;
#endif

struct Request {
    pid_t parent = 0;
    std::uint64_t memory_limit = 0, cpu_seconds = 0;
    kdrt::ImportOptions options;
    std::array<double, 16> transform = kdrt::kIdentityTransform;
    std::string model;
};

[[noreturn]] void usage() {
    std::fputs("kdrt-import: libkdrt's model import helper, started by libkdrt only\n", stderr);
    std::exit(2);
}

std::uint64_t number(const char* text) {
    char* end = nullptr;
    errno = 0;
    const unsigned long long v = std::strtoull(text, &end, 10);
    if (errno || end == text || *end) usage();
    return v;
}

Request parse(int argc, char** argv) {
    Request r;
    r.options.isolation = kdrt::ImportIsolation::InProcess;
    int i = 1;
    for (; i < argc && std::strcmp(argv[i], "--") != 0; ++i) {
        const std::string a = argv[i];
        const bool has_value = i + 1 < argc;
        if (a == "--parent" && has_value) r.parent = static_cast<pid_t>(number(argv[++i]));
        else if (a == "--memory-limit" && has_value) r.memory_limit = number(argv[++i]);
        else if (a == "--cpu-seconds" && has_value) r.cpu_seconds = number(argv[++i]);
        else if (a == "--allow-outside-files") r.options.allow_outside_files = true;
        else if (a == "--transform" && i + 16 < argc) {
            for (double& v : r.transform) {
                char* end = nullptr;
                v = std::strtod(argv[++i], &end);
                if (*end) usage();
            }
        } else {
            usage();
        }
    }
    if (i + 2 != argc || r.parent <= 0) usage();
    r.model = argv[i + 1];
    return r;
}

// Limits first, so that nothing the model makes happen escapes them.
void limit_self(const Request& r) {
    std::signal(SIGINT, SIG_IGN);  // Ctrl-C reaches the whole process group: the parent decides
    std::signal(SIGHUP, SIG_IGN);
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != r.parent) std::_Exit(1);  // the parent is gone already
    const rlimit no_core{0, 0};
    ::setrlimit(RLIMIT_CORE, &no_core);
    if (r.memory_limit && !kAddressSanitizer) {
        const rlimit memory{r.memory_limit, r.memory_limit};
        ::setrlimit(RLIMIT_AS, &memory);
    }
    if (r.cpu_seconds) {
        const rlimit cpu{r.cpu_seconds, r.cpu_seconds + 1};
        ::setrlimit(RLIMIT_CPU, &cpu);
    }
}

std::vector<std::uint8_t> import(const Request& r) {
    try {
        return kdrt::detail::encode_import_result(kdrt::import_model(r.model, r.transform, r.options));
    } catch (const kdrt::Error& e) {
        std::string message = e.what();
        if (e.code() == kdrt::ErrorCode::ResourceLimit)
            message += " (the import's memory limit is " + std::to_string(r.memory_limit >> 20) +
                       " MiB: ImportOptions::memory_limit)";
        return kdrt::detail::encode_import_error(e.code(), message);
    } catch (const std::bad_alloc&) {
        return kdrt::detail::encode_import_error(
            kdrt::ErrorCode::ResourceLimit, r.model + ": out of memory (the import's memory limit is " +
                                                std::to_string(r.memory_limit >> 20) + " MiB: ImportOptions::memory_limit)");
    } catch (const std::exception& e) {
        return kdrt::detail::encode_import_error(kdrt::ErrorCode::InvalidScene, r.model + ": " + e.what());
    }
}

}  // namespace

int main(int argc, char** argv) {
    const Request r = parse(argc, argv);
    limit_self(r);
    const std::vector<std::uint8_t> bytes = import(r);
    for (std::size_t done = 0; done < bytes.size();) {
        const ssize_t n = ::write(STDOUT_FILENO, bytes.data() + done, bytes.size() - done);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) return 1;
        done += static_cast<std::size_t>(n);
    }
    return 0;
}
