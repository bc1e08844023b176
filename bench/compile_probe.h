// Cold kernel compiles. PoCL reads POCL_CACHE_DIR once, when the platform is
// first initialised, so a cold compile cannot be had inside a process that
// has already compiled: each is measured in a child (this executable's hidden
// `probe-compile` command) given an empty kdrt kernel cache and an empty
// POCL_CACHE_DIR. The child renders one pixel, which builds the program that
// the full render would build (the kernel options do not depend on the size).
#pragma once

#include "subprocess.h"

#include <kdrt/render.h>

#include <filesystem>
#include <map>
#include <string>

namespace kdrt::bench {

struct ColdCompile {
    bool ok = false;
    double compile_ms = 0.0;     // clBuildProgram from source, as RenderResult::compile_ms reports it
    double process_ms = 0.0;     // the whole child: platform start, tree, compile, one pixel
    std::string kernel_options;
    std::string error;
};

ColdCompile measure_cold_compile(const std::filesystem::path& scene, const std::string& device, Traversal traversal,
                                 int max_depth, TempDir& scratch);

// The hidden command: renders SCENE at 1x1 and prints {"compile_ms", "cache_hit", "kernel_options"}.
int run_compile_probe(const std::filesystem::path& scene, const std::string& device, const std::string& traversal,
                      int max_depth, const std::filesystem::path& kernel_cache);

// Remembers cold compiles by (device, kernel options): scenes with the same
// effects build the same program, so one measurement serves them all.
class ColdCompileCache {
public:
    const ColdCompile& get(const std::filesystem::path& scene, const std::string& device, Traversal traversal,
                           int max_depth, const std::string& kernel_options, TempDir& scratch);

private:
    std::map<std::pair<std::string, std::string>, ColdCompile> known_;
};

}  // namespace kdrt::bench
