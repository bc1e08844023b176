// The scene wire format (kdrt/scene_wire.h).
//
// Version 1. Integers little-endian, doubles as their IEEE-754 binary64 bit
// patterns stored as little-endian u64, no padding.
//
//   offset size  field
//        0    8  magic "KDRTSCNE" (ASCII)
//        8    4  u32 format version = 1
//       12    8  u64 payload_size
//       20    8  u64 checksum   XXH3-64 (seed 0) of bytes [0, 20) followed by the payload
//       28       payload, exactly payload_size bytes:
//                  string name
//                  camera     position, look_at, up (vec3), f64 fov_y
//                  settings   i32 width, height, max_depth, samples; vec3 background, ambient
//                  u64 n, n x material  string name, vec3 color, f64 diffuse, specular,
//                                       shininess, reflect, transmit, ior
//                  u64 n, n x light     vec3 position, vec3 color
//                  u64 n, n x sphere    vec3 center, f64 radius, u32 material
//                  mesh triangles       (the loose triangles)
//                  u64 n, n x mesh
//                  u64 n, n x added     u8 kind (0 spheres, 1 triangles, 2 mesh, 3 sphere set), u32 first, u32 count
//   string: u64 length, bytes.  vec3: 3 x f64.
//   mesh:   u64 n, n x vec3 position; u64 n, n x vec3 normal;
//           u64 n, n x triangle (3 x u32 v, 3 x u32 n, u32 material)
//
// A count is checked against the bytes left before anything is allocated, so
// a damaged count cannot ask for more memory than the message holds. The
// checksum catches damage, not forgery: the decoded scene still passes
// kdrt::validate and the object-id check of `added` before it is returned.
#include "common/xxh3.h"
#include "scene/object_ids.h"

#include <kdrt/error.h>
#include <kdrt/scene_wire.h>

#include <bit>
#include <cstring>

namespace kdrt {

namespace {

constexpr char kMagic[8] = {'K', 'D', 'R', 'T', 'S', 'C', 'N', 'E'};
constexpr std::uint32_t kVersion = 1;
constexpr std::size_t kChecksumOffset = 20;
constexpr std::size_t kHeaderSize = 28;

class Writer {
public:
    std::vector<std::uint8_t> bytes;

    void u8(std::uint8_t v) { bytes.push_back(v); }
    void u32(std::uint32_t v) {
        for (int i = 0; i < 4; ++i) bytes.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
    }
    void u64(std::uint64_t v) {
        for (int i = 0; i < 8; ++i) bytes.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
    }
    void i32(int v) { u32(static_cast<std::uint32_t>(v)); }
    void f64(double v) { u64(std::bit_cast<std::uint64_t>(v)); }
    void vec3(const glm::dvec3& v) {
        f64(v.x);
        f64(v.y);
        f64(v.z);
    }
    void string(const std::string& s) {
        u64(s.size());
        bytes.insert(bytes.end(), s.begin(), s.end());
    }
    void mesh(const Mesh& m) {
        u64(m.positions.size());
        for (const glm::dvec3& p : m.positions) vec3(p);
        u64(m.normals.size());
        for (const glm::dvec3& n : m.normals) vec3(n);
        u64(m.triangles.size());
        for (const MeshTriangle& t : m.triangles) {
            for (std::uint32_t v : t.v) u32(v);
            for (std::uint32_t n : t.n) u32(n);
            u32(t.material);
        }
    }
};

class Reader {
public:
    Reader(const std::uint8_t* data, std::size_t size, const std::string& origin)
        : data_(data), size_(size), origin_(origin) {}

    Error fail(const std::string& what) const {
        return Error(ErrorCode::InvalidScene, origin_ + ": scene bytes: " + what);
    }
    std::size_t left() const { return size_ - pos_; }

    std::uint8_t u8() {
        need(1, "a byte");
        return data_[pos_++];
    }
    std::uint32_t u32() {
        need(4, "a 32-bit field");
        std::uint32_t v = 0;
        for (int i = 0; i < 4; ++i) v |= std::uint32_t{data_[pos_++]} << (8 * i);
        return v;
    }
    std::uint64_t u64() {
        need(8, "a 64-bit field");
        std::uint64_t v = 0;
        for (int i = 0; i < 8; ++i) v |= std::uint64_t{data_[pos_++]} << (8 * i);
        return v;
    }
    int i32() { return static_cast<int>(u32()); }
    double f64() { return std::bit_cast<double>(u64()); }
    glm::dvec3 vec3() {
        glm::dvec3 v;
        v.x = f64();
        v.y = f64();
        v.z = f64();
        return v;
    }
    std::string string(const char* field) {
        const std::uint64_t n = count(1, field);
        std::string s(reinterpret_cast<const char*>(data_ + pos_), static_cast<std::size_t>(n));
        pos_ += static_cast<std::size_t>(n);
        return s;
    }
    // An element count whose elements (at least item_size bytes each) fit in what is left.
    std::size_t count(std::size_t item_size, const char* field) {
        const std::uint64_t n = u64();
        if (n > left() / item_size)
            throw fail(std::string(field) + ": " + std::to_string(n) + " entries of " + std::to_string(item_size) +
                       " bytes do not fit in the " + std::to_string(left()) + " bytes left (truncated or damaged)");
        return static_cast<std::size_t>(n);
    }
    Mesh mesh(const char* field) {
        Mesh m;
        m.positions.resize(count(24, field));
        for (glm::dvec3& p : m.positions) p = vec3();
        m.normals.resize(count(24, field));
        for (glm::dvec3& n : m.normals) n = vec3();
        m.triangles.resize(count(28, field));
        for (MeshTriangle& t : m.triangles) {
            for (std::uint32_t& v : t.v) v = u32();
            for (std::uint32_t& n : t.n) n = u32();
            t.material = u32();
        }
        return m;
    }

private:
    void need(std::size_t n, const char* what) const {
        if (left() < n) throw fail(std::string("truncated: ") + what + " runs past the end");
    }
    const std::uint8_t* data_;
    std::size_t size_, pos_ = 0;
    const std::string& origin_;
};

std::uint64_t checksum(const std::uint8_t* data, std::size_t size) {
    detail::Xxh3 h;
    h.update(data, kChecksumOffset);
    h.update(data + kHeaderSize, size - kHeaderSize);
    return h.digest();
}

}  // namespace

std::vector<std::uint8_t> serialize_scene(const Scene& scene) {
    Writer w;
    w.bytes.insert(w.bytes.end(), kMagic, kMagic + 8);
    w.u32(kVersion);
    w.u64(0);  // payload_size, patched below
    w.u64(0);  // checksum, patched below

    w.string(scene.name);
    w.vec3(scene.camera.position);
    w.vec3(scene.camera.look_at);
    w.vec3(scene.camera.up);
    w.f64(scene.camera.fov_y);
    const RenderSettings& s = scene.settings;
    w.i32(s.width);
    w.i32(s.height);
    w.i32(s.max_depth);
    w.i32(s.samples);
    w.vec3(s.background);
    w.vec3(s.ambient);
    w.u64(scene.materials.size());
    for (const Material& m : scene.materials) {
        w.string(m.name);
        w.vec3(m.color);
        for (double v : {m.diffuse, m.specular, m.shininess, m.reflect, m.transmit, m.ior}) w.f64(v);
    }
    w.u64(scene.lights.size());
    for (const PointLight& l : scene.lights) {
        w.vec3(l.position);
        w.vec3(l.color);
    }
    w.u64(scene.spheres.size());
    for (const Sphere& sp : scene.spheres) {
        w.vec3(sp.center);
        w.f64(sp.radius);
        w.u32(sp.material);
    }
    w.mesh(scene.triangles);
    w.u64(scene.meshes.size());
    for (const Mesh& m : scene.meshes) w.mesh(m);
    w.u64(scene.added.size());
    for (const AddedObjects& a : scene.added) {
        w.u8(static_cast<std::uint8_t>(a.kind));
        w.u32(a.first);
        w.u32(a.count);
    }

    std::vector<std::uint8_t>& out = w.bytes;
    const std::uint64_t payload = out.size() - kHeaderSize;
    for (int i = 0; i < 8; ++i) out[12 + i] = static_cast<std::uint8_t>(payload >> (8 * i));
    const std::uint64_t sum = checksum(out.data(), out.size());
    for (int i = 0; i < 8; ++i) out[kChecksumOffset + i] = static_cast<std::uint8_t>(sum >> (8 * i));
    return out;
}

Scene deserialize_scene(const std::uint8_t* data, std::size_t size, const std::string& origin) {
    Reader header(data, std::min(size, kHeaderSize), origin);
    if (size < 8 || std::memcmp(data, kMagic, 8) != 0) throw header.fail("not a kdrt scene (bad magic)");
    if (size < kHeaderSize)
        throw header.fail("truncated: " + std::to_string(size) + " bytes, shorter than the " +
                          std::to_string(kHeaderSize) + "-byte header");
    header.u64();  // magic
    const std::uint32_t version = header.u32();
    if (version != kVersion)
        throw header.fail("format version " + std::to_string(version) + ", this build reads version " +
                          std::to_string(kVersion));
    const std::uint64_t payload = header.u64();
    const std::uint64_t stored_sum = header.u64();
    if (payload != size - kHeaderSize)
        throw header.fail("payload of " + std::to_string(payload) + " bytes announced, " +
                          std::to_string(size - kHeaderSize) + " present (truncated or damaged)");
    if (checksum(data, size) != stored_sum) throw header.fail("checksum mismatch (damaged)");

    Reader r(data + kHeaderSize, size - kHeaderSize, origin);
    Scene scene;
    scene.name = r.string("name");
    scene.camera.position = r.vec3();
    scene.camera.look_at = r.vec3();
    scene.camera.up = r.vec3();
    scene.camera.fov_y = r.f64();
    RenderSettings& s = scene.settings;
    s.width = r.i32();
    s.height = r.i32();
    s.max_depth = r.i32();
    s.samples = r.i32();
    s.background = r.vec3();
    s.ambient = r.vec3();
    scene.materials.resize(r.count(8 + 72, "materials"));
    for (Material& m : scene.materials) {
        m.name = r.string("materials[].name");
        m.color = r.vec3();
        for (double* v : {&m.diffuse, &m.specular, &m.shininess, &m.reflect, &m.transmit, &m.ior}) *v = r.f64();
    }
    scene.lights.resize(r.count(48, "lights"));
    for (PointLight& l : scene.lights) {
        l.position = r.vec3();
        l.color = r.vec3();
    }
    scene.spheres.resize(r.count(36, "spheres"));
    for (Sphere& sp : scene.spheres) {
        sp.center = r.vec3();
        sp.radius = r.f64();
        sp.material = r.u32();
    }
    scene.triangles = r.mesh("triangles");
    scene.meshes.resize(r.count(24, "meshes"));
    for (Mesh& m : scene.meshes) m = r.mesh("meshes");
    scene.added.resize(r.count(9, "added"));
    for (AddedObjects& a : scene.added) {
        const std::uint8_t kind = r.u8();
        if (kind > static_cast<std::uint8_t>(AddedObjects::Kind::SphereSet))
            throw r.fail("added: unknown kind " + std::to_string(kind));
        a.kind = static_cast<AddedObjects::Kind>(kind);
        a.first = r.u32();
        a.count = r.u32();
    }
    if (r.left() != 0) throw r.fail(std::to_string(r.left()) + " bytes after the scene (damaged)");
    try {
        validate(scene);
        detail::public_object_ids(scene);  // `added` names objects the scene has, each once
    } catch (const Error& e) {
        throw Error(ErrorCode::InvalidScene, origin + ": " + e.what());
    }
    return scene;
}

}  // namespace kdrt
