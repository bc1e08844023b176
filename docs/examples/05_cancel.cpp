// Cancelling a long render from its progress callback: returning false makes
// the call throw kdrt::Error(Cancelled) soon after, having written nothing.
#include <kdrt/error.h>
#include <kdrt/render.h>
#include <kdrt/scene_loader.h>

#include <cstdio>

int main(int argc, char** argv) {
    kdrt::Scene scene = kdrt::load_scene(argc > 1 ? argv[1] : "scenes/ball-o-calypse.json");
    kdrt::RenderOptions options;
    options.width = 800;
    options.height = 600;
    options.samples = 4;
    double reported = 0.0;
    options.progress = [&reported](double done) {
        reported = done;     // called from the thread that called render()
        return done < 0.25;  // a user pressing "stop" a quarter of the way in
    };
    try {
        kdrt::render(scene, options);
    } catch (const kdrt::Error& e) {
        if (e.code() != kdrt::ErrorCode::Cancelled) throw;
        std::printf("%s at %.0f%%: %s\n", kdrt::to_string(e.code()), 100 * reported, e.what());
        return 0;
    }
    std::printf("the render finished before it was cancelled\n");
    return 1;
}
