#include "scene/model_wire.h"

#include "common/xxh3.h"

#include <kdrt/error.h>
#include <kdrt/scene_wire.h>

#include <bit>
#include <cstring>
#include <utility>

namespace kdrt::detail {
namespace {

constexpr char kMagic[8] = {'K', 'D', 'R', 'T', 'I', 'M', 'P', 'T'};
constexpr std::uint32_t kVersion = 1;

class Put {
public:
    std::vector<std::uint8_t> bytes;
    void u8(std::uint8_t v) { bytes.push_back(v); }
    void u64(std::uint64_t v) {
        for (int i = 0; i < 8; ++i) bytes.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
    }
    void f64(double v) { u64(std::bit_cast<std::uint64_t>(v)); }
    void vec3(const glm::dvec3& v) {
        for (int i = 0; i < 3; ++i) f64(v[i]);
    }
    void string(const std::string& s) {
        u64(s.size());
        bytes.insert(bytes.end(), s.begin(), s.end());
    }
};

class Get {
public:
    Get(const std::uint8_t* data, std::size_t size, const std::string& origin) : data_(data), size_(size), origin_(origin) {}
    Error fail(const std::string& what) const { return Error(ErrorCode::InvalidScene, origin_ + ": import result: " + what); }
    std::size_t left() const { return size_ - pos_; }
    std::uint8_t u8() {
        need(1);
        return data_[pos_++];
    }
    std::uint64_t u64() {
        need(8);
        std::uint64_t v = 0;
        for (int i = 0; i < 8; ++i) v |= std::uint64_t{data_[pos_++]} << (8 * i);
        return v;
    }
    double f64() { return std::bit_cast<double>(u64()); }
    glm::dvec3 vec3() {
        glm::dvec3 v;
        for (int i = 0; i < 3; ++i) v[i] = f64();
        return v;
    }
    // A count of items of at least `item` bytes each that fit in what is left.
    std::size_t count(std::size_t item) {
        const std::uint64_t n = u64();
        if (n > left() / item) throw fail("a count of " + std::to_string(n) + " runs past the end");
        return static_cast<std::size_t>(n);
    }
    std::string string() {
        const std::size_t n = count(1);
        std::string s(reinterpret_cast<const char*>(data_ + pos_), n);
        pos_ += n;
        return s;
    }
    const std::uint8_t* take(std::size_t n) {
        need(n);
        pos_ += n;
        return data_ + pos_ - n;
    }

private:
    void need(std::size_t n) const {
        if (left() < n) throw fail("truncated");
    }
    const std::uint8_t* data_;
    std::size_t size_, pos_ = 0;
    const std::string& origin_;
};

std::uint64_t le64(const std::uint8_t* p) {
    std::uint64_t v = 0;
    for (int i = 7; i >= 0; --i) v = (v << 8) | p[i];
    return v;
}

std::uint64_t checksum(const std::uint8_t* data, std::size_t size) {
    Xxh3 h;
    h.update(data, size);
    return h.digest();
}

// Header and checksum around a payload.
std::vector<std::uint8_t> framed(const std::vector<std::uint8_t>& payload) {
    Put out;
    out.bytes.assign(kMagic, kMagic + 8);
    for (int i = 0; i < 4; ++i) out.u8(static_cast<std::uint8_t>(kVersion >> (8 * i)));
    out.u64(payload.size());
    out.u64(checksum(payload.data(), payload.size()));
    out.bytes.insert(out.bytes.end(), payload.begin(), payload.end());
    return std::move(out.bytes);
}

void put_stats(Put& p, const ImportStats& s) {
    for (std::size_t v : {s.meshes, s.skipped_points, s.skipped_lines, s.skipped_lights, s.flat_triangles}) p.u64(v);
    p.u64(s.warnings.size());
    for (const std::string& w : s.warnings) p.string(w);
}

ImportStats get_stats(Get& g) {
    ImportStats s;
    for (std::size_t* v : {&s.meshes, &s.skipped_points, &s.skipped_lines, &s.skipped_lights, &s.flat_triangles})
        *v = static_cast<std::size_t>(g.u64());
    s.warnings.resize(g.count(8));
    for (std::string& w : s.warnings) w = g.string();
    return s;
}

ImportedModel get_model(Get& g, const std::string& origin) {
    const std::size_t scene_bytes = g.count(1);
    Scene scene = deserialize_scene(g.take(scene_bytes), scene_bytes, origin + ": import result");
    if (scene.meshes.size() != 1 || !scene.spheres.empty() || !scene.triangles.triangles.empty())
        throw g.fail("the scene holds other objects than one mesh");
    ImportedModel model;
    model.mesh = std::move(scene.meshes[0]);
    model.materials = std::move(scene.materials);
    model.lights = std::move(scene.lights);
    model.cameras.resize(g.count(8 + 9 * 8 + 2 * 8 + 1));
    for (ModelCamera& c : model.cameras) {
        c.name = g.string();
        c.camera.position = g.vec3();
        c.camera.look_at = g.vec3();
        c.camera.up = g.vec3();
        c.camera.fov_y = g.f64();
        c.aspect = g.f64();
        c.orthographic = g.u8() != 0;
    }
    model.stats = get_stats(g);
    if (g.left() != 0) throw g.fail(std::to_string(g.left()) + " bytes after the model");
    // What can be derived is derived here, not taken from the bytes.
    for (const glm::dvec3& p : model.mesh.positions) model.bounds.extend(p);
    model.stats.triangles = model.mesh.triangles.size();
    model.stats.materials = model.materials.size();
    model.stats.cameras = model.cameras.size();
    model.stats.lights = model.lights.size();
    return model;
}

}  // namespace

std::vector<std::uint8_t> encode_import_result(ImportedModel&& model) {
    Scene scene;
    scene.materials = std::move(model.materials);
    scene.lights = std::move(model.lights);
    scene.add_mesh(std::move(model.mesh));
    Put p;
    p.u8(0);
    const std::vector<std::uint8_t> scene_bytes = serialize_scene(scene);
    p.u64(scene_bytes.size());
    p.bytes.insert(p.bytes.end(), scene_bytes.begin(), scene_bytes.end());
    p.u64(model.cameras.size());
    for (const ModelCamera& c : model.cameras) {
        p.string(c.name);
        p.vec3(c.camera.position);
        p.vec3(c.camera.look_at);
        p.vec3(c.camera.up);
        p.f64(c.camera.fov_y);
        p.f64(c.aspect);
        p.u8(c.orthographic ? 1 : 0);
    }
    put_stats(p, model.stats);
    return framed(p.bytes);
}

std::vector<std::uint8_t> encode_import_error(ErrorCode code, const std::string& message) {
    Put p;
    p.u8(1);
    p.u64(static_cast<std::uint64_t>(code));
    p.string(message);
    return framed(p.bytes);
}

std::uint64_t import_result_payload_size(const std::uint8_t* header, const std::string& origin) {
    if (std::memcmp(header, kMagic, 8) != 0)
        throw Error(ErrorCode::InvalidScene, origin + ": import result: not a result (bad magic)");
    std::uint32_t version = 0;
    for (int i = 3; i >= 0; --i) version = (version << 8) | header[8 + i];
    if (version != kVersion)
        throw Error(ErrorCode::InvalidScene, origin + ": import result: version " + std::to_string(version) +
                                                 ", expected " + std::to_string(kVersion));
    return le64(header + 12);
}

bool is_complete_import_result(const std::uint8_t* data, std::size_t size) {
    if (size < kImportResultHeaderBytes || std::memcmp(data, kMagic, 8) != 0) return false;
    const std::uint64_t payload = le64(data + 12);
    return payload == size - kImportResultHeaderBytes &&
           checksum(data + kImportResultHeaderBytes, size - kImportResultHeaderBytes) == le64(data + 20);
}

ImportedModel decode_import_result(const std::uint8_t* data, std::size_t size, const std::string& origin) {
    if (size < kImportResultHeaderBytes)
        throw Error(ErrorCode::InvalidScene, origin + ": import result: truncated header");
    const std::uint64_t payload = import_result_payload_size(data, origin);
    Get g(data + kImportResultHeaderBytes, size - kImportResultHeaderBytes, origin);
    if (payload != g.left()) throw g.fail("payload of " + std::to_string(payload) + " bytes announced, " +
                                          std::to_string(g.left()) + " present");
    if (checksum(data + kImportResultHeaderBytes, g.left()) != le64(data + 20)) throw g.fail("checksum mismatch");
    const std::uint8_t kind = g.u8();
    if (kind == 0) return get_model(g, origin);
    if (kind != 1) throw g.fail("unknown kind " + std::to_string(kind));
    const std::uint64_t code = g.u64();
    if (code > static_cast<std::uint64_t>(ErrorCode::ResourceLimit)) throw g.fail("unknown error code");
    throw Error(static_cast<ErrorCode>(code), g.string());
}

}  // namespace kdrt::detail
