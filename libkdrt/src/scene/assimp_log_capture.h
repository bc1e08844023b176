// Assimp reports some of what it fixes silently only to its log: a glTF face
// with an index out of range is dropped with a warning. While an import runs,
// this captures the warnings and errors (nothing is printed), so that such a
// file becomes an error and the rest become ImportStats warnings.
#pragma once

#include <mutex>
#include <string>
#include <vector>

namespace kdrt::detail {

class AssimpLogCapture {
public:
    AssimpLogCapture();   // installs a logger unless the program has its own
    ~AssimpLogCapture();  // removes it again
    AssimpLogCapture(const AssimpLogCapture&) = delete;
    AssimpLogCapture& operator=(const AssimpLogCapture&) = delete;

    // Warning and error messages, without Assimp's "Warn,  T0: " prefix.
    const std::vector<std::string>& messages() const { return messages_; }

private:
    std::unique_lock<std::mutex> lock_;  // Assimp's logger is global: one import at a time logs
    bool installed_ = false;
    std::vector<std::string> messages_;
};

}  // namespace kdrt::detail
