#include "compile_probe.h"

#include <kdrt/error.h>
#include <kdrt/scene_loader.h>

#include <nlohmann/json.hpp>

#include <cstdio>
#include <iostream>

namespace kdrt::bench {

ColdCompile measure_cold_compile(const std::filesystem::path& scene, const std::string& device, Traversal traversal,
                                 int max_depth, TempDir& scratch) {
    ColdCompile c;
    ChildOptions o;
    o.argv = {self_executable().string(), "probe-compile", scene.string(), "--device", device,
              "--traversal", to_string(traversal), "--depth", std::to_string(max_depth),
              "--kernel-cache", scratch.fresh("kernels").string()};
    o.env = {{"POCL_CACHE_DIR", scratch.fresh("pocl").string()}};
    o.timeout_s = 600.0;
    const ChildResult r = run_child(o);
    c.process_ms = r.wall_ms;
    if (r.exit_code != 0) {
        c.error = "probe exited with " + std::to_string(r.exit_code);
        return c;
    }
    try {
        const auto j = nlohmann::json::parse(r.out);
        c.compile_ms = j.at("compile_ms").get<double>();
        c.kernel_options = j.at("kernel_options").get<std::string>();
        c.ok = !j.at("cache_hit").get<bool>();
        if (!c.ok) c.error = "the probe hit a kernel cache";
    } catch (const std::exception& e) {
        c.error = std::string("unreadable probe output: ") + e.what();
    }
    return c;
}

int run_compile_probe(const std::filesystem::path& scene, const std::string& device, const std::string& traversal,
                      int max_depth, const std::filesystem::path& kernel_cache) {
    RenderOptions o;
    o.device = device;
    o.frame.width = o.frame.height = 1;
    o.frame.max_depth = max_depth;
    o.commit.traversal = traversal_from_string(traversal);
    o.commit.kernel_cache_dir = kernel_cache;
    const RenderResult r = render(load_scene(scene), o);
    nlohmann::json j = {{"compile_ms", r.stats.compile_ms}, {"cache_hit", r.stats.opencl.kernel_cache_hit}, {"kernel_options", r.stats.opencl.kernel_options}};
    std::cout << j.dump() << std::endl;
    return 0;
}

const ColdCompile& ColdCompileCache::get(const std::filesystem::path& scene, const std::string& device,
                                         Traversal traversal, int max_depth, const std::string& kernel_options,
                                         TempDir& scratch) {
    const auto key = std::make_pair(device, kernel_options);
    auto it = known_.find(key);
    if (it == known_.end()) it = known_.emplace(key, measure_cold_compile(scene, device, traversal, max_depth, scratch)).first;
    return it->second;
}

}  // namespace kdrt::bench
