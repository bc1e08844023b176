// kdrt::Error: the one exception type that crosses the library's edge.
// User and environment failures (bad scene, corrupt tree file, unknown device,
// failed kernel build) are reported with a code and a message that names the
// problem; the CLI turns them into messages and exit codes.
#pragma once

#include <kdrt/export.h>

#include <stdexcept>
#include <string>

namespace kdrt {

enum class ErrorCode {
    InvalidScene,     // malformed or out-of-range scene description
    Io,               // a file could not be read or written
    InvalidArgument,  // a bad option value passed to the library
    CorruptTree,      // a serialized kd-tree failed its checks
    Device,           // device selection, OpenCL runtime or kernel build failure
    Unsupported,      // a valid request this build or device cannot honour
    Cancelled,        // the caller cancelled a long operation (a kd-tree build)
    ResourceLimit,    // a configured memory budget would be exceeded
};

KDRT_API const char* to_string(ErrorCode code);

class KDRT_API Error : public std::runtime_error {
public:
    Error(ErrorCode code, const std::string& message)
        : std::runtime_error(message), code_(code) {}
    ErrorCode code() const { return code_; }

private:
    ErrorCode code_;
};

}  // namespace kdrt
