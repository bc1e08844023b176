// An imported model placed in a scene (add_model), or made a whole scene
// with docs/IMPORT.md's default camera, light and settings (scene_from_model).
#include <kdrt/error.h>
#include <kdrt/model_import.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <set>
#include <string>
#include <utility>

namespace kdrt {
namespace {

constexpr double kPi = 3.14159265358979323846;

// docs/IMPORT.md, "Default camera and light".
constexpr double kDefaultFovY = 40.0;       // degrees
constexpr double kFrameMargin = 1.1;        // the bounding sphere fills 1/1.1 of the narrower field of view
const glm::dvec3 kViewFrom{0.5, 0.5, 1.0};  // from the front (+z), a little right and above
constexpr int kDefaultHeight = 500;
const glm::dvec3 kBackground{0.1};
const glm::dvec3 kAmbient{0.1};

glm::dvec3 centre_of(const Aabb& b) { return b.empty() ? glm::dvec3(0.0) : (b.lo + b.hi) * 0.5; }

// Half the diagonal, made positive for a model that is a single point.
double radius_of(const Aabb& b) {
    const double r = b.empty() ? 0.0 : 0.5 * glm::length(b.extent());
    if (r > 0.0 && std::isfinite(r)) return r;
    return std::max(1.0, 1e-6 * glm::length(centre_of(b)));
}

std::string camera_label(int index, const ModelCamera& c) {
    std::string label = "camera " + std::to_string(index);
    if (!c.name.empty()) label += " ('" + c.name + "')";
    return label;
}

// Why a file's camera breaks FORMAT.md's camera rules, or empty.
std::string camera_problem(const ModelCamera& c) {
    Scene probe;
    probe.camera = c.camera;
    try {
        validate(probe);
    } catch (const Error& e) {
        return e.what();
    }
    return {};
}

// The file's camera that options pick, or -1 for the default camera. Without
// a choice, the first perspective camera that passes FORMAT.md's rules; the
// ones passed over for their values are warnings.
int pick_camera(const std::filesystem::path& path, ImportedModel& model, const ModelSceneOptions& options) {
    const int count = static_cast<int>(model.cameras.size());
    if (!options.camera) {
        for (int i = 0; i < count; ++i) {
            const ModelCamera& c = model.cameras[static_cast<std::size_t>(i)];
            if (c.orthographic) continue;
            const std::string problem = camera_problem(c);
            if (problem.empty()) return i;
            model.stats.warnings.push_back(path.string() + ": " + camera_label(i, c) + " not used (" + problem + ")");
        }
        return -1;
    }
    const int n = *options.camera;
    if (n < 0 || n >= count)
        throw Error(ErrorCode::InvalidArgument,
                    path.string() + ": camera " + std::to_string(n) + " requested, but the file has " +
                        (count == 0 ? std::string("no cameras") : std::to_string(count) + " (0.." + std::to_string(count - 1) + ")"));
    if (model.cameras[static_cast<std::size_t>(n)].orthographic)
        throw Error(ErrorCode::Unsupported, path.string() + ": " + camera_label(n, model.cameras[static_cast<std::size_t>(n)]) +
                                                " is orthographic; kdrt has pinhole cameras only");
    return n;
}

// The file's camera must pass FORMAT.md's camera rules like a scene file's.
void check_camera(const std::filesystem::path& path, int index, const ModelCamera& c) {
    if (const std::string problem = camera_problem(c); !problem.empty())
        throw Error(ErrorCode::InvalidScene, path.string() + ": " + camera_label(index, c) + ": " + problem);
}

// The default image for a camera's aspect ratio: 500 pixels high, as wide as
// the aspect asks within FORMAT.md's 16384 (clamped before rounding: an
// aspect of 1e30 would overflow the rounding).
int width_for_aspect(double aspect) {
    return static_cast<int>(std::lround(std::clamp(kDefaultHeight * aspect, 1.0, 16384.0)));
}

}  // namespace

Camera default_model_camera(const Aabb& bounds, double aspect) {
    if (!(aspect > 0.0) || !std::isfinite(aspect)) aspect = 1.0;
    const double half_y = kDefaultFovY * kPi / 360.0;
    const double half_x = std::atan(std::tan(half_y) * aspect);
    const double half = std::min(half_x, half_y);
    Camera c;
    c.look_at = centre_of(bounds);
    c.position = c.look_at + glm::normalize(kViewFrom) * (kFrameMargin * radius_of(bounds) / std::sin(half));
    c.up = {0.0, 1.0, 0.0};
    c.fov_y = kDefaultFovY;
    return c;
}

PointLight default_model_light(const Camera& camera, const Aabb& bounds) {
    const glm::dvec3 forward = glm::normalize(camera.look_at - camera.position);
    const glm::dvec3 right = glm::normalize(glm::cross(forward, camera.up));
    const glm::dvec3 up = glm::cross(right, forward);
    PointLight light;
    light.position = camera.position + up * radius_of(bounds);
    light.color = glm::dvec3(1.0);
    return light;
}

std::uint32_t add_model(Scene& scene, ImportedModel model, std::optional<MaterialId> override_material) {
    if (override_material) {
        if (*override_material >= scene.materials.size())
            throw Error(ErrorCode::InvalidArgument, "add_model: material " + std::to_string(*override_material) + " out of range");
        for (MeshTriangle& t : model.mesh.triangles) t.material = *override_material;
        return scene.add_mesh(std::move(model.mesh));
    }
    std::set<std::string> taken;
    for (const Material& m : scene.materials) taken.insert(m.name);
    const auto base = static_cast<MaterialId>(scene.materials.size());
    for (Material& m : model.materials) {
        std::string name = m.name;
        for (int k = 2; taken.count(name) > 0; ++k) name = m.name + "#" + std::to_string(k);
        taken.insert(name);
        m.name = std::move(name);
        scene.add_material(std::move(m));
    }
    for (MeshTriangle& t : model.mesh.triangles) t.material += base;
    return scene.add_mesh(std::move(model.mesh));
}

Scene scene_from_model(const std::filesystem::path& path, const ModelSceneOptions& options, ImportStats* stats) {
    ImportedModel model = import_model(path, kIdentityTransform, options.import);
    Scene scene;
    scene.name = path.stem().string();
    scene.settings.background = kBackground;
    scene.settings.ambient = kAmbient;

    const int picked = pick_camera(path, model, options);
    if (picked >= 0) {
        const ModelCamera& c = model.cameras[static_cast<std::size_t>(picked)];
        check_camera(path, picked, c);
        scene.camera = c.camera;
        if (c.aspect > 0.0) {
            scene.settings.height = kDefaultHeight;
            scene.settings.width = width_for_aspect(c.aspect);
        }
    } else {
        scene.camera = default_model_camera(model.bounds, 1.0);
    }
    scene.lights = model.lights;
    if (scene.lights.empty()) scene.lights.push_back(default_model_light(scene.camera, model.bounds));

    if (stats) *stats = model.stats;
    add_model(scene, std::move(model));
    try {
        validate(scene);
    } catch (const Error& e) {
        throw Error(e.code(), path.string() + ": " + e.what());
    }
    return scene;
}

}  // namespace kdrt
