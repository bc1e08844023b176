// Commits a scene to a device once and renders three frames of a camera path:
// the BVH is built once, each frame uploads only the new camera.
#include <kdrt/committed_scene.h>
#include <kdrt/device.h>
#include <kdrt/image.h>
#include <kdrt/scene_loader.h>

#include <cmath>
#include <cstdio>
#include <string>

int main(int argc, char** argv) {
    kdrt::Scene scene = kdrt::load_scene(argc > 1 ? argv[1] : "scenes/lens.json");
    kdrt::Device device = kdrt::Device::open();  // $KDRT_DEVICE, else "cpu"
    kdrt::CommittedScene committed = kdrt::CommittedScene::commit(device, scene);

    kdrt::FrameOptions frame;
    frame.width = 200;
    frame.height = 150;
    for (int i = 0; i < 3; ++i) {
        double angle = 0.15 * i;
        scene.camera.position = {4 * std::sin(angle), 0.3, -4 * std::cos(angle)};
        committed.update(scene);  // camera, lights, materials: no rebuild
        kdrt::RenderResult result = committed.render(frame);
        kdrt::write_image("02_frame" + std::to_string(i) + ".png", result.image);
        std::printf("frame %d: %.1f ms on %s\n", i, result.stats.render_ms, result.stats.device_name.c_str());
    }

    const kdrt::CommitStats& stats = committed.stats();
    std::printf("%llu tree build(s) in %.1f ms, %llu geometry upload(s), %llu shading upload(s)\n",
                static_cast<unsigned long long>(stats.builds), stats.build_ms,
                static_cast<unsigned long long>(stats.geometry_uploads),
                static_cast<unsigned long long>(stats.shading_uploads));
    return stats.builds == 1 ? 0 : 1;
}
