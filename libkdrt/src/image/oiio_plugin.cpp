#include "image/oiio_plugin.h"

#include <kdrt/error.h>

#include <dlfcn.h>

#include <algorithm>
#include <cstdlib>

#include <filesystem>
#include <mutex>
#include <vector>

namespace kdrt::detail {

namespace {

namespace fs = std::filesystem;

constexpr const char* kPluginName = "libkdrt_oiio.so";

bool inside(const fs::path& file, const fs::path& dir) {
    const auto [d, f] = std::mismatch(dir.begin(), dir.end(), file.begin(), file.end());
    return d == dir.end();
}

std::vector<fs::path> candidates() {
    if (const char* env = std::getenv("KDRT_OIIO_PLUGIN"); env && *env) return {fs::path(env)};
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    fs::path self;  // libkdrt.so, or the program libkdrt is linked into
    Dl_info info{};
    if (dladdr(reinterpret_cast<void*>(&candidates), &info) && info.dli_fname && *info.dli_fname)
        self = fs::weakly_canonical(fs::absolute(info.dli_fname, ec), ec);
    if (self.empty()) self = exe;
    std::vector<fs::path> list;
#ifdef KDRT_OIIO_PLUGIN_BUILD_PATH
    const fs::path build_dir = KDRT_BUILD_DIR;
    if ((!self.empty() && inside(self, build_dir)) || (!exe.empty() && inside(exe, build_dir)))
        list.emplace_back(KDRT_OIIO_PLUGIN_BUILD_PATH);
#endif
    if (!self.empty()) list.push_back(self.parent_path() / kPluginName);
    if (!exe.empty()) list.push_back((exe.parent_path() / KDRT_BINDIR_TO_LIBDIR / kPluginName).lexically_normal());
    list.push_back(fs::path(KDRT_INSTALL_FULL_LIBDIR) / kPluginName);
    return list;
}

const KdrtOiioPlugin* load(std::string& problem) {
    std::string looked;
    for (const fs::path& file : candidates()) {
        std::error_code ec;
        if (!fs::exists(file, ec)) {
            looked += (looked.empty() ? "" : ", ") + file.string();
            continue;
        }
        void* handle = dlopen(file.c_str(), RTLD_NOW | RTLD_LOCAL);
        if (!handle) {
            const char* e = dlerror();
            problem = file.string() + " cannot be loaded: " + (e ? e : "unknown error");
            return nullptr;
        }
        using Entry = const KdrtOiioPlugin* (*)();
        const auto entry = reinterpret_cast<Entry>(dlsym(handle, KDRT_OIIO_PLUGIN_SYMBOL));
        const KdrtOiioPlugin* plugin = entry ? entry() : nullptr;
        if (!plugin || plugin->abi_version != KDRT_OIIO_ABI_VERSION) {
            problem = file.string() + " is not a libkdrt_oiio plugin of this libkdrt version";
            dlclose(handle);
            return nullptr;
        }
        return plugin;  // kept loaded for the life of the process
    }
    problem = std::string(kPluginName) + " (kdrt's OpenImageIO plugin) is not installed; looked for " + looked +
              " (KDRT_OIIO_PLUGIN may name it)";
    return nullptr;
}

}  // namespace

const KdrtOiioPlugin& oiio_plugin(const std::string& why) {
    static std::mutex mutex;
    static const KdrtOiioPlugin* plugin = nullptr;
    const std::lock_guard lock(mutex);
    if (!plugin) {
        std::string problem;
        plugin = load(problem);
        if (!plugin) throw Error(ErrorCode::Io, why + " needs OpenImageIO: " + problem);
    }
    return *plugin;
}

}  // namespace kdrt::detail
