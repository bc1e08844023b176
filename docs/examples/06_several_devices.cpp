// One frame shared by every device of the machine: tiles are handed out one
// at a time, so a faster device takes more of them.
#include <kdrt/image.h>
#include <kdrt/scene_loader.h>
#include <kdrt/tiled_render.h>

#include <cstdio>
#include <vector>

int main(int argc, char** argv) {
    kdrt::Scene scene = kdrt::load_scene(argc > 1 ? argv[1] : "scenes/lens.json");
    std::vector<kdrt::Device> devices = kdrt::open_devices("all");  // cpu, then each OpenCL device
    kdrt::MultiDeviceScene multi = kdrt::MultiDeviceScene::commit(devices, scene);  // one tree build

    kdrt::FrameOptions frame;
    frame.width = 320;
    frame.height = 240;
    kdrt::RenderResult result = multi.render(frame, kdrt::TileSize{32, 32});
    kdrt::write_image("06_several_devices.png", result.image);

    unsigned long long pixels = 0;
    for (const kdrt::DeviceShare& d : result.stats.device_shares) {
        std::printf("%s: %llu tiles, %.1f ms busy\n", d.device_name.c_str(),
                    static_cast<unsigned long long>(d.tiles), d.busy_ms);
        pixels += d.pixels;
    }
    return pixels == 320ull * 240 ? 0 : 1;
}
