#include "render.h"

#include "arrays.h"
#include "raycasting_scene.h"

#include <kdrt/committed_scene.h>
#include <kdrt/error.h>
#include <kdrt/model_import.h>
#include <kdrt/scene.h>
#include <kdrt/scene_loader.h>

#include <nanobind/stl/string.h>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <filesystem>
#include <thread>

namespace kdrt::python {

namespace {

// A progress callback that cancels once Python has a pending signal (Ctrl-C).
// Python runs signal handlers in its main thread only: the check is made when
// kdrt calls back from the thread that called render(), which holds the GIL
// for it; calls from builder threads report the last answer.
struct Interrupt {
    std::thread::id caller = std::this_thread::get_id();
    std::atomic<bool> raised{false};

    bool operator()(double) {
        if (raised) return false;
        if (std::this_thread::get_id() != caller) return true;
        nb::gil_scoped_acquire gil;
        if (PyErr_CheckSignals() != 0) raised = true;  // the KeyboardInterrupt stays pending
        return !raised;
    }
};

Scene load(const std::string& path) {
    const std::filesystem::path p(path);
    return is_model_file(p) ? scene_from_model(p) : load_scene(p);
}

nb::dict render_scene(const Scene& scene, const std::string& device, int width, int height, int samples,
                      int max_depth, int threads) {
    if (width < 0 || height < 0 || samples < 0 || max_depth < 0 || threads < 0)
        throw nb::value_error("width, height, samples, max_depth and threads must be >= 0 (0: the scene's own)");
    FrameOptions frame;
    frame.width = width;
    frame.height = height;
    frame.samples = samples;
    frame.max_depth = max_depth;
    frame.threads = threads;
    frame.want_ids = true;
    Interrupt interrupt;
    CommitOptions commit;
    commit.progress = [&](double done) { return interrupt(done); };
    frame.progress = [&](double done) { return interrupt(done); };
    RenderResult r;
    try {
        nb::gil_scoped_release nogil;
        const Device d = open_device(device.empty() ? "cpu" : device);
        r = CommittedScene::commit(d, scene, commit).render(frame);
    } catch (const Error& e) {
        if (e.code() == ErrorCode::Cancelled && interrupt.raised) throw nb::python_error();
        throw;
    }
    const auto h = static_cast<std::size_t>(r.image.height), w = static_cast<std::size_t>(r.image.width);
    auto image = new_array<float>({h, w, 3});
    auto ids = new_array<std::int32_t>({h, w});
    auto t_hit = new_array<float>({h, w});
    std::copy(r.image.rgb.begin(), r.image.rgb.end(), image.data());
    std::copy(r.ids.begin(), r.ids.end(), ids.data());
    std::copy(r.hit_t.begin(), r.hit_t.end(), t_hit.data());
    nb::dict stats;
    stats["device"] = r.stats.device_name;
    stats["build_ms"] = r.stats.build_ms;
    stats["render_ms"] = r.stats.render_ms;
    stats["rays"] = r.stats.rays.total();
    nb::dict out;
    out["image"] = image;
    out["ids"] = ids;
    out["t_hit"] = t_hit;
    out["stats"] = stats;
    return out;
}

}  // namespace

void bind_render(nb::module_& m) {
    nb::class_<Scene>(m, "Scene", "A scene to render: a scene file (FORMAT.md) or a model file, loaded.")
        .def_ro("name", &Scene::name)
        .def_prop_ro("width", [](const Scene& s) { return s.settings.width; })
        .def_prop_ro("height", [](const Scene& s) { return s.settings.height; })
        .def_prop_ro("object_count", [](const Scene& s) { return s.object_count(); })
        .def("__repr__", [](const Scene& s) {
            return "<kdrt.Scene '" + s.name + "': " + std::to_string(s.object_count()) + " objects, " +
                   std::to_string(s.settings.width) + "x" + std::to_string(s.settings.height) + ">";
        });
    m.def(
        "load_scene",
        [](const std::string& path) {
            nb::gil_scoped_release nogil;
            return load(path);
        },
        nb::arg("path"),
        "Loads a scene file (.json, FORMAT.md) or a model file (.glb, .gltf, .obj, .ply, .stl, .off, .fbx) "
        "with its materials, camera and lights or IMPORT.md's defaults.");
    m.def("_render", &render_scene, nb::arg("scene"), nb::arg("device") = "cpu", nb::arg("width") = 0,
          nb::arg("height") = 0, nb::arg("samples") = 0, nb::arg("max_depth") = 0, nb::arg("threads") = 0);
}

}  // namespace kdrt::python
