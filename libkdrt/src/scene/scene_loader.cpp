// JSON scene loader for FORMAT.md "kdrt-scene/1".
//
// Strict by design: a typo in a key, a vector of the wrong length or a number
// where a string belongs is an error, never a silently different picture.
// Every message reads "<file>: <place>: <problem>", place being a JSON path
// such as "spheres[3].radius" or "materials.glass.ior".
#include "common/printable_text.h"
#include "common/read_input_file.h"
#include "scene/affine_transform.h"
#include "scene/json_depth.h"

#include <kdrt/error.h>
#include <kdrt/model_import.h>
#include <kdrt/scene.h>
#include <kdrt/scene_loader.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstring>
#include <initializer_list>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <unordered_set>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace kdrt {
namespace {

// ordered_json keeps the file order of materials, so their ids follow the file.
using Json = nlohmann::ordered_json;

// Keys come from the file: quoted printably (no terminal escapes) and bounded.
std::string join(const std::string& place, std::string_view key) {
    const std::string k = detail::printable(key);
    return place.empty() ? k : place + "." + k;
}

std::string at_index(const std::string& place, std::size_t i) {
    return place + "[" + std::to_string(i) + "]";
}

std::string number_text(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

// Nesting deeper than this is refused: no scene needs more than a handful of
// levels, and the limit bounds the parser's stack and the length of places.
constexpr std::size_t kMaxJsonDepth = 64;

// Longest place ("spheres[3].radius") quoted in a syntax error message.
constexpr std::size_t kMaxPlaceChars = 160;

// Builds the document from nlohmann's SAX events, linear in the file size.
// (nlohmann's callback parser, used before for the places, re-walks the parent
// after every value and was quadratic; ordered_json's own insert is a linear
// duplicate search per key.) It also records the JSON path being parsed, so
// that errors the parser itself raises (syntax, number overflow), duplicate
// keys (nlohmann would silently keep the last) and too deep a nesting are
// reported with a place.
class DocumentBuilder final : public nlohmann::json_sax<Json> {
public:
    enum class Failure { None, Syntax, Overflow, Duplicate, TooDeep };

    Json root;
    Failure failure = Failure::None;
    std::size_t failure_byte = 0;  // 1-based byte offset, for Syntax and Overflow
    std::string failure_detail;

    bool null() override { return add(Json(nullptr)); }
    bool boolean(bool v) override { return add(Json(v)); }
    bool number_integer(number_integer_t v) override { return add(Json(v)); }
    bool number_unsigned(number_unsigned_t v) override { return add(Json(v)); }
    bool number_float(number_float_t v, const string_t&) override { return add(Json(v)); }
    bool string(string_t& v) override { return add(Json(std::move(v))); }
    bool binary(binary_t&) override { return false; }  // JSON text has no binary values

    bool start_object(std::size_t) override { return open(Json::object()); }
    bool start_array(std::size_t) override { return open(Json::array()); }
    bool end_object() override { return close(); }
    bool end_array() override { return close(); }

    bool key(string_t& k) override {
        Frame& top = frames_.back();
        if (top.is_duplicate(k)) {
            top.pending_key = std::move(k);
            top.has_pending_key = true;
            failure = Failure::Duplicate;
            return false;
        }
        top.pending_key = std::move(k);
        top.has_pending_key = true;
        return true;
    }

    bool parse_error(std::size_t position, const std::string&, const nlohmann::detail::exception& e) override {
        // 406 is the one non-syntax failure: a number too large for a double.
        failure = e.id == 406 ? Failure::Overflow : Failure::Syntax;
        failure_byte = position;
        failure_detail = e.what();
        return false;
    }

    // The member or element being parsed right now, e.g. "spheres[3].radius".
    std::string place() const {
        std::string p;
        for (std::size_t k = 0; k < frames_.size(); ++k) {
            const Frame& f = frames_[k];
            // An open child is already the array's last element; a scalar being
            // parsed is not in it yet.
            if (f.value->is_array()) {
                p = at_index(p, f.value->size() - (k + 1 < frames_.size() ? 1 : 0));
            } else if (f.has_pending_key) {
                p = join(p, f.pending_key);
            } else if (const auto& members = f.members(); !members.empty()) {
                p = join(p, members.back().first);
            }
        }
        return p;
    }

private:
    using Members = Json::object_t::Container;

    struct Frame {
        Json* value;                  // the open object or array
        std::string pending_key;      // objects: the key whose value comes next
        bool has_pending_key = false;
        // Keys of a large object, for the duplicate test; small ones are scanned.
        std::unique_ptr<std::unordered_set<std::string>> keys;

        const Members& members() const { return static_cast<const Members&>(value->get_ref<const Json::object_t&>()); }

        bool is_duplicate(const std::string& k) {
            const Members& m = members();
            if (!keys && m.size() < 16) {
                return std::any_of(m.begin(), m.end(), [&](const auto& member) { return member.first == k; });
            }
            if (!keys) {
                keys = std::make_unique<std::unordered_set<std::string>>();
                for (const auto& member : m) keys->insert(member.first);
            }
            return !keys->insert(k).second;
        }
    };

    // Places a complete or just-opened value into the open container; returns
    // where it now lives (stable until that container gets its next element,
    // which cannot happen while the value is still open).
    Json* place_value(Json&& v) {
        if (frames_.empty()) {
            root = std::move(v);
            return &root;
        }
        Json& parent = *frames_.back().value;
        if (parent.is_array()) {
            parent.get_ref<Json::array_t&>().push_back(std::move(v));
            return &parent.get_ref<Json::array_t&>().back();
        }
        // Duplicates were refused in key(): append without ordered_map's search.
        Frame& top = frames_.back();
        auto& members = static_cast<Members&>(parent.get_ref<Json::object_t&>());
        members.emplace_back(std::move(top.pending_key), std::move(v));
        top.has_pending_key = false;
        return &members.back().second;
    }

    bool add(Json&& v) {
        place_value(std::move(v));
        return true;
    }

    bool open(Json&& container) {
        if (frames_.size() >= kMaxJsonDepth) {
            failure = Failure::TooDeep;
            return false;
        }
        Json* v = place_value(std::move(container));
        frames_.push_back({v, {}, false, nullptr});
        return true;
    }

    bool close() {
        frames_.pop_back();
        return true;
    }

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
// keep only the description after that, quoting file text printably.
std::string nlohmann_detail(const std::string& what) {
    std::size_t bracket = what.find("] ");
    std::string rest = bracket == std::string::npos ? what : what.substr(bracket + 2);
    std::size_t colon = rest.find(": ");
    if (rest.rfind("parse error", 0) == 0 && colon != std::string::npos) rest = rest.substr(colon + 2);
    // "last read: '<token>'" can quote a whole string token.
    return detail::printable(rest, 200);
}

// The innermost end of a long place is the informative one.
std::string bounded_place(const std::string& place) {
    if (place.size() <= kMaxPlaceChars) return place;
    return "..." + place.substr(place.size() - kMaxPlaceChars);
}

// Builds a Scene from the parsed document; owns the error formatting.
class SceneReader {
public:
    SceneReader(std::string origin, std::filesystem::path base_dir, const SceneLoadOptions& options)
        : origin_(std::move(origin)), base_dir_(std::move(base_dir)), options_(options) {}

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
        if (it == material_ids_.end()) fail(where, "undefined material '" + detail::printable(name) + "'");
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
    const SceneLoadOptions& options_;
    std::map<std::string, MaterialId> material_ids_;
};

Scene SceneReader::read(const Json& root) {
    expect_object(root, "");
    // The format is checked first: a file of another version should say so
    // rather than complain about keys it does not know.
    const Json* format = optional(root, "format");
    if (!format) fail("format", "missing (expected \"kdrt-scene/1\")");
    std::string fmt = string(*format, "format");
    if (fmt != "kdrt-scene/1") fail("format", "unsupported \"" + detail::printable(fmt) + "\", expected \"kdrt-scene/1\"");
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
        check_keys(j[i], place, {"obj", "model", "material", "transform"});
        // "obj": the strict OBJ subset below, one material for every face.
        // "model": any file Assimp reads (docs/IMPORT.md) with its own
        // materials, unless "material" overrides them.
        const bool is_model = optional(j[i], "model") != nullptr;
        if (is_model && optional(j[i], "obj")) fail(place, "has both \"obj\" and \"model\": give one");
        const std::string file_place = join(place, is_model ? "model" : "obj");
        std::string file = string(required(j[i], place, is_model ? "model" : "obj"), file_place);
        if (file.empty()) fail(file_place, "empty path");
        if (file.find('\0') != std::string::npos)
            fail(file_place, "'" + detail::printable(file) + "': a path cannot contain a NUL byte");
        std::optional<MaterialId> material;
        if (!is_model || optional(j[i], "material")) material = material_ref(j[i], place);
        std::array<double, 16> transform = kIdentityTransform;
        if (const Json* t = optional(j[i], "transform"))
            transform = read_transform(*t, join(place, "transform"));
        // The loaders' errors already name the file (and line); add where it was used.
        try {
            if (is_model) {
                ImportedModel model = import_model(base_dir_ / file, transform, options_.import);
                if (options_.warnings)
                    for (const std::string& w : model.stats.warnings) options_.warnings->push_back(origin_ + ": " + file_place + ": " + w);
                add_model(scene, std::move(model), material);
            } else {
                scene.add_mesh(load_obj_mesh(base_dir_ / file, transform, *material));
            }
        } catch (const Error& e) {
            fail(file_place, e.what(), e.code());
        }
    }
}

}  // namespace

Scene parse_scene(const std::string& json_text, const std::filesystem::path& base_dir, const std::string& origin,
                  const SceneLoadOptions& options) {
    DocumentBuilder builder;
    const bool ok = Json::sax_parse(json_text, &builder);
    const std::string near = bounded_place(builder.place());
    const std::string at_near = near.empty() ? "" : near + ": ";
    switch (builder.failure) {
        case DocumentBuilder::Failure::None: break;
        case DocumentBuilder::Failure::Duplicate:
            throw Error(ErrorCode::InvalidScene, origin + ": " + at_near + "duplicate key");
        case DocumentBuilder::Failure::TooDeep: {
            auto [line, column] = line_column(json_text, detail::json_depth_exceeded_at(json_text, kMaxJsonDepth));
            throw Error(ErrorCode::InvalidScene,
                        origin + ": line " + std::to_string(line) + ", column " + std::to_string(column) + ", " +
                            at_near + "nested deeper than " + std::to_string(kMaxJsonDepth) + " levels");
        }
        case DocumentBuilder::Failure::Overflow:
            // FORMAT.md numbers must be finite.
            throw Error(ErrorCode::InvalidScene, origin + ": " + at_near + "must be a finite number (" +
                                                     nlohmann_detail(builder.failure_detail) + ")");
        case DocumentBuilder::Failure::Syntax: {
            auto [line, column] = line_column(json_text, builder.failure_byte);
            throw Error(ErrorCode::InvalidScene,
                        origin + ": line " + std::to_string(line) + ", column " + std::to_string(column) +
                            " (byte " + std::to_string(builder.failure_byte) + ")" +
                            (near.empty() ? "" : ", near " + near) +
                            ": JSON syntax error: " + nlohmann_detail(builder.failure_detail));
        }
    }
    if (!ok) throw Error(ErrorCode::InvalidScene, origin + ": JSON parsing stopped without a reason");
    return SceneReader(origin, base_dir, options).read(builder.root);
}

Scene load_scene(const std::filesystem::path& path, const SceneLoadOptions& options) {
    return parse_scene(detail::read_input_file(path, "scene file"), path.parent_path(), path.string(), options);
}

}  // namespace kdrt
