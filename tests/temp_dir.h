// A per-process scratch folder for tests that write files: ctest may run test
// cases in parallel, so each process gets its own, removed at the end.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>

namespace kdrt::test {

struct TempDir {
    std::filesystem::path path;
    explicit TempDir(const std::string& prefix)
        : path(std::filesystem::temp_directory_path() / (prefix + "-" + std::to_string(::getpid()))) {
        std::filesystem::remove_all(path);
        std::filesystem::create_directories(path);
    }
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(path, ec);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;
    std::filesystem::path write(const std::string& name, const std::string& bytes) const {
        std::filesystem::path p = path / name;
        std::ofstream(p, std::ios::binary) << bytes;
        return p;
    }
};

}  // namespace kdrt::test
