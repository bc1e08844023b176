// libFuzzer target: scene JSON text through kdrt::parse_scene. Any input may
// be rejected with kdrt::Error; anything else (a crash, a sanitizer report, a
// hang, another exception type) is a finding. OBJ paths resolve against a
// folder holding one small valid mesh, "ok.obj", so meshes are exercised too.
#include <kdrt/error.h>
#include <kdrt/scene_loader.h>

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace {

std::filesystem::path mesh_folder() {
    static const std::filesystem::path dir = [] {
        std::filesystem::path d =
            std::filesystem::temp_directory_path() / ("kdrt-fuzz-scene-" + std::to_string(::getpid()));
        std::filesystem::create_directories(d);
        std::ofstream(d / "ok.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\n";
        return d;
    }();
    return dir;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    try {
        kdrt::parse_scene(text, mesh_folder(), "fuzz.json");
    } catch (const kdrt::Error&) {
    }
    return 0;
}
