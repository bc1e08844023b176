// Cancelling a long frame from its progress callback: returning false makes
// the call throw kdrt::Error(Cancelled) soon after, having written nothing.
#include <kdrt/committed_scene.h>
#include <kdrt/device.h>
#include <kdrt/error.h>
#include <kdrt/scene_loader.h>

#include <cstdio>

int main(int argc, char** argv) {
    kdrt::Scene scene = kdrt::load_scene(argc > 1 ? argv[1] : "scenes/ball-o-calypse.json");
    kdrt::CommittedScene committed = kdrt::CommittedScene::commit(kdrt::Device::open(), scene);

    kdrt::FrameOptions frame;
    frame.width = 800;
    frame.height = 600;
    frame.samples = 4;
    double reported = 0.0;
    frame.progress = [&reported](double done) {
        reported = done;
        return done < 0.25;  // a user pressing "stop" a quarter of the way in
    };
    try {
        committed.render(frame);
    } catch (const kdrt::Error& e) {
        if (e.code() != kdrt::ErrorCode::Cancelled) throw;
        std::printf("%s at %.0f%%: %s\n", kdrt::to_string(e.code()), 100 * reported, e.what());
        return 0;
    }
    std::printf("the frame finished before it was cancelled\n");
    return 1;
}
