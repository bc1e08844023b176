// JSON scene loader for FORMAT.md "kdrt-scene/1".
//
// Strict by design: a typo in a key, a vector of the wrong length or a number
// where a string belongs is an error, never a silently different picture.
// Every message reads "<file>: <place>: <problem>", place being a JSON path
// such as "spheres[3].radius" or "materials.glass.ior".
#include "scene/affine_transform.h"

#include <kdrt/error.h>
#include <kdrt/scene.h>
#include <kdrt/scene_loader.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstring>
#include <fstream>
#include <initializer_list>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace kdrt {
namespace {

// ordered_json keeps the file order of materials, so their ids follow the file.
using Json = nlohmann::ordered_json;

std::string join(const std::string& place, std::string_view key) {
    return place.empty() ? std::string(key) : place + "." + std::string(key);
}

std::string at_index(const std::string& place, std::size_t i) {
    return place + "[" + std::to_string(i) + "]";
}

std::string number_text(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

// Tracks the JSON path while nlohmann parses, so that errors the parser itself
// raises (syntax, number overflow) and duplicate keys, which nlohmann would
// silently resolve to the last one, can be reported with a place.
class PathTracker {
public:
    explicit PathTracker(const std::string& origin) : origin_(origin) {}

    bool on_event(Json::parse_event_t event, const Json& parsed) {
        using E = Json::parse_event_t;
        switch (event) {
            case E::object_start: frames_.push_back({false, 0, {}, {}}); break;
            case E::array_start: frames_.push_back({true, 0, {}, {}}); break;
            case E::key: {
                Frame& top = frames_.back();
                top.key = parsed.get<std::string>();
                if (!top.keys.insert(top.key).second)
                    throw Error(ErrorCode::InvalidScene,
                                origin_ + ": " + path() + ": duplicate key");
                break;
            }
            case E::object_end:
            case E::array_end:
                frames_.pop_back();
                element_done();
                break;
            case E::value: element_done(); break;
        }
        return true;
    }

    // The member or element being parsed right now.
    std::string path() const {
        std::string p;
        for (const Frame& f : frames_) {
            if (f.array)
                p = at_index(p, f.index);
            else if (!f.key.empty() || !f.keys.empty())
                p = join(p, f.key);
        }
        return p;
    }

private:
    struct Frame {
        bool array;
        std::size_t index;      // arrays: index of the element being parsed
        std::string key;        // objects: last key seen
        std::set<std::string> keys;
    };

    void element_done() {
        if (!frames_.empty() && frames_.back().array) ++frames_.back().index;
    }

    const std::string& origin_;
    std::vector<Frame> frames_;
};

// Line and column (both 1-based) of a 1-based byte offset as nlohmann reports it.
std::pair<std::size_t, std::size_t> line_column(const std::string& text, std::size_t byte) {
    std::size_t end = std::min(byte > 0 ? byte - 1 : 0, text.size());
    std::size_t line = 1, line_start = 0;
    for (std::size_t i = 0; i < end; ++i)
        if (text[i] == '\n') {
            ++line;
            line_start = i + 1;
        }
    return {line, end - line_start + 1};
}

// nlohmann's what() starts with "[json.exception.x.n] parse error at ...: ";
// keep only the description after that.
std::string nlohmann_detail(const std::string& what) {
    std::size_t bracket = what.find("] ");
    if (bracket == std::string::npos) return what;
    std::string rest = what.substr(bracket + 2);
    std::size_t colon = rest.find(": ");
    if (rest.rfind("parse error", 0) == 0 && colon != std::string::npos) return rest.substr(colon + 2);
    return rest;
}

// Builds a Scene from the parsed document; owns the error formatting.
class SceneReader {
public:
    SceneReader(std::string origin, std::filesystem::path base_dir)
        : origin_(std::move(origin)), base_dir_(std::move(base_dir)) {}

    Scene read(const Json& root);

private:
    [[noreturn]] void fail(const std::string& place, const std::string& what,
                           ErrorCode code = ErrorCode::InvalidScene) const {
        throw Error(code, origin_ + ": " + (place.empty() ? "" : place + ": ") + what);
    }

    // --- typed access ---------------------------------------------------

    void expect_object(const Json& j, const std::string& place) const {
        if (!j.is_object()) fail(place, std::string("expected an object, got ") + j.type_name());
    }

    void expect_array(const Json& j, const std::string& place) const {
        if (!j.is_array()) fail(place, std::string("expected an array, got ") + j.type_name());
    }

    // Rejects keys outside `allowed`, listing what would have been accepted.
    void check_keys(const Json& obj, const std::string& place,
                    std::initializer_list<std::string_view> allowed) const {
        for (const auto& item : obj.items()) {
            if (std::find(allowed.begin(), allowed.end(), item.key()) != allowed.end()) continue;
            std::string list;
            for (std::string_view a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
            fail(join(place, item.key()), "unknown key (allowed: " + list + ")");
        }
    }

    const Json* optional(const Json& obj, std::string_view key) const {
        auto it = obj.find(key);
        return it == obj.end() ? nullptr : &*it;
    }

    const Json& required(const Json& obj, const std::string& place, std::string_view key) const {
        const Json* j = optional(obj, key);
        if (!j) fail(join(place, key), "missing (required)");
        return *j;
    }

    double number(const Json& j, const std::string& place) const {
        if (!j.is_number()) fail(place, std::string("expected a number, got ") + j.type_name());
        double v = j.get<double>();
        if (!std::isfinite(v)) fail(place, "must be a finite number, got " + number_text(v));
        return v;
    }

    // Integral JSON number that fits an int; the range rules are validate()'s.
    int integer(const Json& j, const std::string& place) const {
        double v = number(j, place);
        if (v != std::floor(v)) fail(place, "must be an integer, got " + number_text(v));
        if (v < double(INT_MIN) || v > double(INT_MAX))
            fail(place, "integer out of range, got " + number_text(v));
        return static_cast<int>(v);
    }

    std::string string(const Json& j, const std::string& place) const {
        if (!j.is_string()) fail(place, std::string("expected a string, got ") + j.type_name());
        return j.get<std::string>();
    }

    glm::dvec3 vec3(const Json& j, const std::string& place) const {
        if (!j.is_array() || j.size() != 3) {
            std::string got = j.is_array() ? std::to_string(j.size()) + " elements"
                                           : std::string(j.type_name());
            fail(place, "expected an array of 3 numbers, got " + got);
        }
        return {number(j[0], at_index(place, 0)), number(j[1], at_index(place, 1)),
                number(j[2], at_index(place, 2))};
    }

    MaterialId material_ref(const Json& obj, const std::string& place) const {
        std::string where = join(place, "material");
        std::string name = string(required(obj, place, "material"), where);
        auto it = material_ids_.find(name);
        if (it == material_ids_.end()) fail(where, "undefined material '" + name + "'");
        return it->second;
    }

    // --- sections -------------------------------------------------------

    void read_camera(const Json& j, Camera& cam) const;
    void read_settings(const Json& j, RenderSettings& s) const;
    void read_materials(const Json& j, Scene& scene);
    void read_lights(const Json& j, Scene& scene) const;
    void read_spheres(const Json& j, Scene& scene) const;
    void read_triangles(const Json& j, Scene& scene) const;
    void read_meshes(const Json& j, Scene& scene) const;
    std::array<double, 16> read_transform(const Json& j, const std::string& place) const;

    std::string origin_;
    std::filesystem::path base_dir_;
    std::map<std::string, MaterialId> material_ids_;
};

Scene SceneReader::read(const Json& root) {
    expect_object(root, "");
    // The format is checked first: a file of another version should say so
    // rather than complain about keys it does not know.
    const Json* format = optional(root, "format");
    if (!format) fail("format", "missing (expected \"kdrt-scene/1\")");
    std::string fmt = string(*format, "format");
    if (fmt != "kdrt-scene/1") fail("format", "unsupported \"" + fmt + "\", expected \"kdrt-scene/1\"");
    check_keys(root, "", {"format", "name", "camera", "settings", "materials", "lights", "spheres",
                          "triangles", "meshes"});

    Scene scene;
    if (const Json* name = optional(root, "name")) scene.name = string(*name, "name");
    read_camera(required(root, "", "camera"), scene.camera);
    if (const Json* s = optional(root, "settings")) read_settings(*s, scene.settings);
    if (const Json* m = optional(root, "materials")) read_materials(*m, scene);
    if (const Json* l = optional(root, "lights")) read_lights(*l, scene);
    if (const Json* s = optional(root, "spheres")) read_spheres(*s, scene);
    if (const Json* t = optional(root, "triangles")) read_triangles(*t, scene);
    if (const Json* m = optional(root, "meshes")) read_meshes(*m, scene);

    // Ranges, camera sanity and limits are validate()'s job; its places
    // ("spheres[3].radius") match the file because everything kept file order.
    try {
        validate(scene);
    } catch (const Error& e) {
        fail("", e.what(), e.code());
    }
    return scene;
}

void SceneReader::read_camera(const Json& j, Camera& cam) const {
    const std::string place = "camera";
    expect_object(j, place);
    check_keys(j, place, {"position", "look_at", "up", "fov_y"});
    // No defaults in FORMAT.md's camera table: every key is required.
    cam.position = vec3(required(j, place, "position"), "camera.position");
    cam.look_at = vec3(required(j, place, "look_at"), "camera.look_at");
    cam.up = vec3(required(j, place, "up"), "camera.up");
    cam.fov_y = number(required(j, place, "fov_y"), "camera.fov_y");
}

void SceneReader::read_settings(const Json& j, RenderSettings& s) const {
    const std::string place = "settings";
    expect_object(j, place);
    check_keys(j, place, {"width", "height", "max_depth", "samples", "background", "ambient"});
    if (const Json* v = optional(j, "width")) s.width = integer(*v, "settings.width");
    if (const Json* v = optional(j, "height")) s.height = integer(*v, "settings.height");
    if (const Json* v = optional(j, "max_depth")) s.max_depth = integer(*v, "settings.max_depth");
    if (const Json* v = optional(j, "samples")) s.samples = integer(*v, "settings.samples");
    if (const Json* v = optional(j, "background")) s.background = vec3(*v, "settings.background");
    if (const Json* v = optional(j, "ambient")) s.ambient = vec3(*v, "settings.ambient");
}

void SceneReader::read_materials(const Json& j, Scene& scene) {
    expect_object(j, "materials");
    for (const auto& item : j.items()) {
        const std::string& name = item.key();
        const std::string place = join("materials", name);
        // Scene::add_material renames an unnamed material, which would break
        // the name lookup below.
        if (name.empty()) fail("materials", "material name must not be empty");
        const Json& mj = item.value();
        expect_object(mj, place);
        check_keys(mj, place,
                   {"color", "diffuse", "specular", "shininess", "reflect", "transmit", "ior"});
        Material m;
        m.name = name;
        if (const Json* v = optional(mj, "color")) m.color = vec3(*v, join(place, "color"));
        if (const Json* v = optional(mj, "diffuse")) m.diffuse = number(*v, join(place, "diffuse"));
        if (const Json* v = optional(mj, "specular")) m.specular = number(*v, join(place, "specular"));
        if (const Json* v = optional(mj, "shininess")) m.shininess = number(*v, join(place, "shininess"));
        if (const Json* v = optional(mj, "reflect")) m.reflect = number(*v, join(place, "reflect"));
        if (const Json* v = optional(mj, "transmit")) m.transmit = number(*v, join(place, "transmit"));
        if (const Json* v = optional(mj, "ior")) m.ior = number(*v, join(place, "ior"));
        material_ids_[name] = scene.add_material(std::move(m));
    }
}

void SceneReader::read_lights(const Json& j, Scene& scene) const {
    expect_array(j, "lights");
    for (std::size_t i = 0; i < j.size(); ++i) {
        const std::string place = at_index("lights", i);
        expect_object(j[i], place);
        check_keys(j[i], place, {"position", "color"});
        PointLight light;
        light.position = vec3(required(j[i], place, "position"), join(place, "position"));
        light.color = vec3(required(j[i], place, "color"), join(place, "color"));
        scene.add_light(light);
    }
}

void SceneReader::read_spheres(const Json& j, Scene& scene) const {
    expect_array(j, "spheres");
    for (std::size_t i = 0; i < j.size(); ++i) {
        const std::string place = at_index("spheres", i);
        expect_object(j[i], place);
        check_keys(j[i], place, {"center", "radius", "material"});
        glm::dvec3 center = vec3(required(j[i], place, "center"), join(place, "center"));
        double radius = number(required(j[i], place, "radius"), join(place, "radius"));
        scene.add_sphere(center, radius, material_ref(j[i], place));
    }
}

void SceneReader::read_triangles(const Json& j, Scene& scene) const {
    expect_array(j, "triangles");
    for (std::size_t i = 0; i < j.size(); ++i) {
        const std::string place = at_index("triangles", i);
        expect_object(j[i], place);
        check_keys(j[i], place, {"v", "material"});
        const std::string vplace = join(place, "v");
        const Json& v = required(j[i], place, "v");
        if (!v.is_array() || v.size() != 3) {
            std::string got = v.is_array() ? std::to_string(v.size()) + " elements"
                                           : std::string(v.type_name());
            fail(vplace, "expected an array of 3 points, got " + got);
        }
        scene.add_triangle(vec3(v[0], at_index(vplace, 0)), vec3(v[1], at_index(vplace, 1)),
                           vec3(v[2], at_index(vplace, 2)), material_ref(j[i], place));
    }
}

std::array<double, 16> SceneReader::read_transform(const Json& j, const std::string& place) const {
    if (!j.is_array() || j.size() != 16) {
        std::string got = j.is_array() ? std::to_string(j.size()) + " elements"
                                       : std::string(j.type_name());
        fail(place, "expected an array of 16 numbers (4x4 row-major), got " + got);
    }
    std::array<double, 16> m{};
    for (std::size_t k = 0; k < 16; ++k) m[k] = number(j[k], at_index(place, k));
    if (const std::string problem = detail::affine_transform_problem(m); !problem.empty()) fail(place, problem);
    return m;
}

void SceneReader::read_meshes(const Json& j, Scene& scene) const {
    expect_array(j, "meshes");
    for (std::size_t i = 0; i < j.size(); ++i) {
        const std::string place = at_index("meshes", i);
        expect_object(j[i], place);
        check_keys(j[i], place, {"obj", "material", "transform"});
        const std::string obj_place = join(place, "obj");
        std::string obj = string(required(j[i], place, "obj"), obj_place);
        if (obj.empty()) fail(obj_place, "empty path");
        MaterialId material = material_ref(j[i], place);
        std::array<double, 16> transform{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
        if (const Json* t = optional(j[i], "transform"))
            transform = read_transform(*t, join(place, "transform"));
        // OBJ errors already name the OBJ file (and line); add where it was used.
        try {
            scene.add_mesh(load_obj_mesh(base_dir_ / obj, transform, material));
        } catch (const Error& e) {
            fail(obj_place, e.what(), e.code());
        }
    }
}

}  // namespace

Scene parse_scene(const std::string& json_text, const std::filesystem::path& base_dir,
                  const std::string& origin) {
    PathTracker tracker(origin);
    Json root;
    try {
        root = Json::parse(json_text, [&](int, Json::parse_event_t event, Json& parsed) {
            return tracker.on_event(event, parsed);
        });
    } catch (const Json::parse_error& e) {
        auto [line, column] = line_column(json_text, e.byte);
        std::string near = tracker.path();
        throw Error(ErrorCode::InvalidScene,
                    origin + ": line " + std::to_string(line) + ", column " + std::to_string(column) +
                        " (byte " + std::to_string(e.byte) + ")" +
                        (near.empty() ? "" : ", near " + near) +
                        ": JSON syntax error: " + nlohmann_detail(e.what()));
    } catch (const Json::exception& e) {
        // Number overflow (e.g. 1e999) is the one non-syntax parse failure:
        // FORMAT.md numbers must be finite.
        std::string near = tracker.path();
        throw Error(ErrorCode::InvalidScene,
                    origin + ": " + (near.empty() ? "" : near + ": ") +
                        "must be a finite number (" + nlohmann_detail(e.what()) + ")");
    }
    return SceneReader(origin, base_dir).read(root);
}

Scene load_scene(const std::filesystem::path& path) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec))
        throw Error(ErrorCode::Io, path.string() + ": is a directory, not a scene file");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(ErrorCode::Io, path.string() + ": cannot open: " + std::strerror(errno));
    std::ostringstream text;
    text << in.rdbuf();
    if (in.bad()) throw Error(ErrorCode::Io, path.string() + ": read failed");
    return parse_scene(text.str(), path.parent_path(), path.string());
}

}  // namespace kdrt
