// Milliseconds of the steady clock since `start`: how the library times its
// builds, uploads, launches and frames.
#pragma once

#include <chrono>

namespace kdrt::detail {

inline double ms_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace kdrt::detail
