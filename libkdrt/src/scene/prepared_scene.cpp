#include "scene/prepared_scene.h"

#include "common/parallel_chunks.h"
#include "common/tsan_fork_join.h"
#include "common/xxh3.h"
#include "scene/object_ids.h"
#include "scene/scene_validation.h"

#include <kdrt/enum_names.h>
#include <kdrt/error.h>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <cstdio>
#include <cstring>
#include <iterator>

namespace kdrt::detail {

namespace {

// Rounds a box outward to float-representable values: a float copy of any
// point inside the double box then lies inside the result. The nearest float
// f of v is within half a step of it; moving f by |f| 2^-22 (at least two
// steps) plus the smallest normal float (for f near 0) lands at least one
// step beyond v, and one more step covers vertices that were themselves
// rounded to float. No branches: the builders' clips call this for every
// straddling object, and stepping on the bits costs a visible part of a build.
inline float float_below(double v) {
    const float f = static_cast<float>(v);
    return f - (std::abs(f) * 0x1p-22f + std::numeric_limits<float>::min());
}
inline float float_above(double v) {
    const float f = static_cast<float>(v);
    return f + (std::abs(f) * 0x1p-22f + std::numeric_limits<float>::min());
}
Aabb round_outward(const Aabb& b) {
    Aabb r;
    for (int a = 0; a < 3; ++a) {
        r.lo[a] = float_below(b.lo[a]);
        r.hi[a] = float_above(b.hi[a]);
    }
    return r;
}

// A convex polygon with room for a triangle clipped by six planes (each
// plane adds at most one vertex): no allocation in the builders' hot loop.
// Points are plain arrays: the clips index them by axis, which glm's
// operator[] does through a switch.
using ClipPoint = std::array<double, 3>;
struct ClipPolygon {
    std::array<ClipPoint, 9> v;
    int n = 0;
};

// Aabb::extend over ClipPoints, with glm::min's and glm::max's comparisons
// (so the same box, signed zeros included), without glm's vector plumbing.
struct ClipBox {
    ClipPoint lo{kInf, kInf, kInf}, hi{-kInf, -kInf, -kInf};
    static constexpr double kInf = std::numeric_limits<double>::infinity();
    void extend(const ClipPoint& p) {
        for (std::size_t k = 0; k < 3; ++k) {
            lo[k] = p[k] < lo[k] ? p[k] : lo[k];
            hi[k] = hi[k] < p[k] ? p[k] : hi[k];
        }
    }
    Aabb aabb() const { return {{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}}; }
};

// Sutherland-Hodgman clipping of a convex polygon against one axis-aligned
// half-space: hands the clipped polygon's vertices, in order, to `emit`.
template <class Emit>
void clip_polygon_to(const ClipPolygon& poly, int axis, double value, bool keep_below, Emit&& emit) {
    auto inside = [&](const ClipPoint& p) { return keep_below ? p[axis] <= value : p[axis] >= value; };
    for (int i = 0; i < poly.n; ++i) {
        const ClipPoint& a = poly.v[static_cast<std::size_t>(i)];
        const ClipPoint& b = poly.v[static_cast<std::size_t>(i + 1 == poly.n ? 0 : i + 1)];
        bool ia = inside(a), ib = inside(b);
        if (ia) emit(a);
        if (ia != ib) {
            const double t = (value - a[axis]) / (b[axis] - a[axis]);
            ClipPoint p;
            for (std::size_t k = 0; k < 3; ++k) p[k] = a[k] + t * (b[k] - a[k]);
            p[axis] = value;
            emit(p);
        }
    }
}

void clip_polygon(const ClipPolygon& poly, ClipPolygon& out, int axis, double value, bool keep_below) {
    out.n = 0;
    clip_polygon_to(poly, axis, value, keep_below,
                    [&](const ClipPoint& p) { out.v[static_cast<std::size_t>(out.n++)] = p; });
}

// One mesh's triangles into g.triangles from `first` on (sized by the
// caller), their shading normals appended to g.normals. In parallel over
// fixed chunks: each chunk's normals go after those of the chunks before it
// (counted first), so the arrays are the same as a serial fill's.
template <class Real>
void fill_mesh(SceneGeometry<Real>& g, const Mesh& mesh, std::size_t first, const glm::dvec3& origin) {
    using Vec = glm::vec<3, Real>;
    auto has_normals = [](const MeshTriangle& t) {
        return t.n[0] != kNoNormal && t.n[1] != kNoNormal && t.n[2] != kNoNormal;
    };
    std::vector<std::size_t> normals_before(chunk_count(mesh.triangles.size()) + 1, 0);
    if (!mesh.normals.empty()) {
        for_each_chunk(mesh.triangles.size(), [&](std::size_t c, std::size_t begin, std::size_t end) {
            std::size_t count = 0;
            for (std::size_t i = begin; i < end; ++i) count += has_normals(mesh.triangles[i]) ? 3 : 0;
            normals_before[c + 1] = count;
        });
        for (std::size_t c = 1; c < normals_before.size(); ++c) normals_before[c] += normals_before[c - 1];
    }
    const std::size_t normal_base = g.normals.size();  // below 2^32: 3 per object, validate() allows 2^30 - 1
    g.normals.resize(normal_base + normals_before.back());
    for_each_chunk(mesh.triangles.size(), [&](std::size_t c, std::size_t begin, std::size_t end) {
        std::size_t next_normal = normal_base + normals_before[c];
        for (std::size_t i = begin; i < end; ++i) {
            const MeshTriangle& t = mesh.triangles[i];
            typename SceneGeometry<Real>::TriangleData d{Vec(mesh.positions[t.v[0]] - origin),
                                                         Vec(mesh.positions[t.v[1]] - origin),
                                                         Vec(mesh.positions[t.v[2]] - origin), t.material, kNoNormal};
            if (has_normals(t)) {
                d.normals = static_cast<std::uint32_t>(next_normal);
                for (std::uint32_t n : t.n) g.normals[next_normal++] = Vec(glm::normalize(mesh.normals[n]));
            }
            g.triangles[first + i] = d;
        }
    });
}

template <class Real>
void fill_geometry(SceneGeometry<Real>& g, const Scene& scene, const glm::dvec3& origin) {
    g.spheres.reserve(scene.spheres.size());
    for (const Sphere& s : scene.spheres)
        g.spheres.push_back({glm::vec<3, Real>(s.center - origin), static_cast<Real>(s.radius), s.material});
    g.triangles.resize(scene.triangle_count());
    std::size_t first = 0;
    fill_mesh(g, scene.triangles, first, origin);
    first += scene.triangles.size();
    for (const Mesh& m : scene.meshes) {
        fill_mesh(g, m, first, origin);
        first += m.size();
    }
}

// XXH3-64 of the float positions and sizes (not materials or normals, which
// leave the tree unchanged), fed in fixed-size chunks of plain floats.
std::uint64_t geometry_fingerprint(const SceneGeometry<float>& g) {
    Xxh3 hash;
    std::vector<float> chunk;
    chunk.reserve(9 * 4096);
    auto flush = [&] {
        hash.update(chunk.data(), chunk.size() * sizeof(float));
        chunk.clear();
    };
    for (const auto& s : g.spheres) {
        chunk.insert(chunk.end(), {s.center.x, s.center.y, s.center.z, s.radius});
        if (chunk.size() >= 9 * 4096 - 9) flush();
    }
    for (const auto& t : g.triangles) {
        chunk.insert(chunk.end(), {t.v0.x, t.v0.y, t.v0.z, t.v1.x, t.v1.y, t.v1.z, t.v2.x, t.v2.y, t.v2.z});
        if (chunk.size() >= 9 * 4096 - 9) flush();
    }
    flush();
    const std::uint64_t counts[2] = {g.spheres.size(), g.triangles.size()};
    hash.update(counts, sizeof(counts));
    return hash.digest();
}

// Enum fields set by a cast from an integer (the public API) hold any value:
// refuse the ones that name no enumerator before a switch meets them.
template <class E>
void check_enum(E value, const char* field) {
    const int v = static_cast<int>(value), count = static_cast<int>(std::size(EnumTable<E>::names));
    if (v < 0 || v >= count)
        throw Error(ErrorCode::InvalidArgument, std::string(field) + " is " + std::to_string(v) +
                                                    ", not one of its " + std::to_string(count) + " values");
}

void check_enums(const CommitOptions& o) {
    check_enum(o.accel, "CommitOptions::accel");
    check_enum(o.traversal, "CommitOptions::traversal");
    check_enum(o.accuracy.precision, "CommitOptions::accuracy.precision");
    check_enum(o.accuracy.triangle_test, "CommitOptions::accuracy.triangle_test");
    check_enum(o.accuracy.sphere_test, "CommitOptions::accuracy.sphere_test");
    check_enum(o.accuracy.self_intersection, "CommitOptions::accuracy.self_intersection");
    check_enum(o.tree.builder, "CommitOptions::tree.builder");
}

// A BVH is walked with a stack, or not at all; the other traversals are the kd-tree's.
void check_accel(const CommitOptions& o) {
    if (o.accel == Accel::Bvh && !bvh_has_traversal(o.traversal))
        throw Error(ErrorCode::InvalidArgument, std::string("the BVH has no ") + to_string(o.traversal) +
                                                    " traversal, only stack and none: the " + to_string(o.traversal) +
                                                    " traversal walks a kd-tree (CommitOptions::accel = Accel::KdTree)");
}

// The watertight triangle test multiplies two coordinates taken from the ray
// origin: in float, beyond 1e18 from the working frame's centre the product
// leaves the float range and the triangle is never hit (a ground of half-size
// 1e18 under the camera renders, 1e19 is all background: a test). Spheres
// are worked in a scaled frame and keep the 1e30 range. Such scenes are
// refused in float, with the way out.
constexpr double kFloatTriangleReach = 1e18;

[[noreturn]] void refuse_float_reach(const std::string& scene_name, const std::string& what, double reach) {
    char text[256];
    std::snprintf(text, sizeof text,
                  " reaches %g units from the scene's centre, beyond the %g that float precision can "
                  "intersect triangles in; render with precision double (--precision double)",
                  reach, kFloatTriangleReach);
    throw Error(ErrorCode::InvalidScene, "scene '" + scene_name + "': " + what + text);
}

// How far a mesh's used vertices (inside `box`) reach from the working
// frame's origin: the largest coordinate of |v - origin|. That is largest at
// a side of the box, and rounding keeps the order, so the box gives what a
// walk over the vertices would.
double reach_of(const Aabb& box, const glm::dvec3& origin) {
    if (box.empty()) return 0.0;
    const glm::dvec3 lo = glm::abs(box.lo - origin), hi = glm::abs(box.hi - origin);
    return std::max({lo.x, lo.y, lo.z, hi.x, hi.y, hi.z});
}

void check_float_triangle_reach(const Scene& scene, const std::vector<Aabb>& mesh_boxes, const glm::dvec3& origin) {
    if (double r = reach_of(mesh_boxes[0], origin); r > kFloatTriangleReach)
        refuse_float_reach(scene.name, "triangles", r);
    for (std::size_t i = 0; i < scene.meshes.size(); ++i)
        if (double r = reach_of(mesh_boxes[i + 1], origin); r > kFloatTriangleReach)
            refuse_float_reach(scene.name, "meshes[" + std::to_string(i) + "]", r);
}

// The box of the vertices a mesh's triangles use; chunks in parallel, their
// boxes combined in chunk order (so even a signed zero ends as a serial walk's).
Aabb used_vertex_box(const Mesh& m) {
    std::vector<Aabb> boxes(chunk_count(m.triangles.size()));
    for_each_chunk(m.triangles.size(), [&](std::size_t c, std::size_t begin, std::size_t end) {
        Aabb b;
        for (std::size_t i = begin; i < end; ++i)
            for (std::uint32_t v : m.triangles[i].v) b.extend(m.positions[v]);
        boxes[c] = b;
    });
    Aabb box;
    for (const Aabb& b : boxes) box.extend(b);
    return box;
}

// 1 + the largest material id the float geometry's objects use (0 without objects).
std::size_t material_refs(const SceneGeometry<float>& g) {
    std::uint32_t refs = 0;
    for (const auto& sphere : g.spheres) refs = std::max(refs, sphere.material + 1u);
    std::vector<std::uint32_t> chunk_refs(chunk_count(g.triangles.size()), 0);
    for_each_chunk(g.triangles.size(), [&](std::size_t c, std::size_t begin, std::size_t end) {
        std::uint32_t r = 0;
        for (std::size_t i = begin; i < end; ++i) r = std::max(r, g.triangles[i].material + 1u);
        chunk_refs[c] = r;
    });
    for (std::uint32_t r : chunk_refs) refs = std::max(refs, r);
    return refs;
}

// The camera in the working frame, with triangles to intersect in float.
void check_float_camera_reach(const std::string& scene_name, const glm::dvec3& camera) {
    const glm::dvec3 c = glm::abs(camera);
    if (std::max({c.x, c.y, c.z}) > kFloatTriangleReach)
        refuse_float_reach(scene_name, "camera.position", std::max({c.x, c.y, c.z}));
}

}  // namespace

void check_frame_options(const FrameOptions& frame) {
    check_enum(frame.opencl.schedule, "FrameOptions::opencl.schedule");
    check_enum(frame.opencl.ray_order, "FrameOptions::opencl.ray_order");
}

RenderSettings frame_settings(const RenderSettings& scene_settings, const FrameOptions& options,
                              const std::string& scene_name) {
    RenderSettings settings = scene_settings;
    if (options.width < 0 || options.height < 0 || options.max_depth < 0 || options.samples < 0)
        throw Error(ErrorCode::InvalidArgument, "width, height, max_depth and samples must not be negative");
    if (options.threads < 0 || options.threads > 1024)
        throw Error(ErrorCode::InvalidArgument,
                    "threads is " + std::to_string(options.threads) + ", must be in [0, 1024] (0: all cores)");
    if (options.width) settings.width = options.width;
    if (options.height) settings.height = options.height;
    if (options.max_depth) settings.max_depth = options.max_depth;
    if (options.samples) settings.samples = options.samples;
    // Name where an out-of-range value came from: the option or the scene's settings.
    auto origin = [&](int option, const char* option_name, const char* setting) {
        return option ? std::string(option_name) : "scene '" + scene_name + "': settings." + setting;
    };
    if (settings.width > 16384)
        throw Error(ErrorCode::InvalidArgument, origin(options.width, "width", "width") + " is " +
                                                    std::to_string(settings.width) + ", at most 16384");
    if (settings.height > 16384)
        throw Error(ErrorCode::InvalidArgument, origin(options.height, "height", "height") + " is " +
                                                    std::to_string(settings.height) + ", at most 16384");
    if (settings.samples > 4096)
        throw Error(ErrorCode::InvalidArgument, origin(options.samples, "samples", "samples") + " is " +
                                                    std::to_string(settings.samples) + ", at most 4096");
    if (settings.max_depth > KDRT_MAX_RAY_DEPTH)
        throw Error(ErrorCode::InvalidArgument, origin(options.max_depth, "max_depth", "max_depth") + " is " +
                                                    std::to_string(settings.max_depth) + ", at most " +
                                                    std::to_string(KDRT_MAX_RAY_DEPTH));
    return settings;
}

PreparedScene prepare_scene(const Scene& scene, const CommitOptions& options, const FrameOptions& frame) {
    validate(scene);
    PreparedScene p;
    (void)frame_settings(scene.settings, frame, scene.name);  // its errors first; prepare_shading() sets them
    check_enums(options);
    check_accel(options);
    options.tree.validate();  // both builders' settings, whichever structure is built
    options.bvh.validate();
    if (!(std::isfinite(options.accuracy.fixed_epsilon) && options.accuracy.fixed_epsilon > 0.0))
        throw Error(ErrorCode::InvalidArgument, "fixed_epsilon must be a positive finite number");

    // World-space bounds of all objects decide the working frame.
    Aabb world;
    for (const Sphere& s : scene.spheres) {
        world.extend(s.center - glm::dvec3(s.radius));
        world.extend(s.center + glm::dvec3(s.radius));
    }
    std::vector<Aabb> mesh_boxes{used_vertex_box(scene.triangles)};  // the loose triangles, then each mesh
    for (const Mesh& m : scene.meshes) mesh_boxes.push_back(used_vertex_box(m));
    for (const Aabb& b : mesh_boxes) world.extend(b);
    if (world.empty()) {
        p.frame_origin = scene.camera.position;
        p.extent = 1.0;
    } else {
        p.frame_origin = 0.5 * (world.lo + world.hi);
        glm::dvec3 e = world.extent();
        p.extent = std::max({e.x, e.y, e.z});
        if (!(p.extent > 0.0)) p.extent = std::max(1.0, glm::length(p.frame_origin)) * 1e-6;
        p.bounds = {world.lo - p.frame_origin, world.hi - p.frame_origin};
        // Geometry, trees and device buffers hold floats: a scene whose extent
        // does not fit would silently turn into infinities.
        if (!(p.extent < 1e30) || !(std::max(glm::length(world.lo), glm::length(world.hi)) < 1e300))
        {
            char sizes[96];
            std::snprintf(sizes, sizeof sizes, "span %g units and reach %g from the origin", p.extent,
                          std::max(glm::length(world.lo), glm::length(world.hi)));
            throw Error(ErrorCode::InvalidScene, "scene '" + scene.name + "': the objects " + sizes +
                                                     ", more than the float range kdrt works in (1e30)");
        }
    }

    if (options.accuracy.precision == Precision::Float) check_float_triangle_reach(scene, mesh_boxes, p.frame_origin);

    fill_geometry(p.geometry_f, scene, p.frame_origin);
    if (options.accuracy.precision == Precision::Double) {
        fill_geometry(p.geometry_d, scene, p.frame_origin);
        p.has_double_geometry = true;
    }
    p.fingerprint = geometry_fingerprint(p.geometry_f);
    p.public_ids = public_object_ids(scene);
    p.geometry_first = geometry_first_ids(scene);
    p.material_refs = material_refs(p.geometry_f);
    prepare_shading(scene, options, frame, p).move_into(p);
    return p;
}

void PreparedScene::name_object(std::uint32_t internal, std::uint32_t& object, std::uint32_t& geometry,
                                std::uint32_t& primitive) const {
    object = public_id(internal);
    const GeometryPrimitive g = geometry_primitive(geometry_first, object);
    geometry = g.geometry;
    primitive = g.primitive;
}

std::vector<std::uint32_t> PreparedScene::name_table() const {
    std::vector<std::uint32_t> names;
    if (public_ids.empty() && geometry_first.empty()) return names;
    const std::uint32_t objects = geometry_f.object_count();
    names.resize(3 * std::size_t{objects});
    for (std::uint32_t i = 0; i < objects; ++i) name_object(i, names[3 * i], names[3 * i + 1], names[3 * i + 2]);
    return names;
}

PreparedShading prepare_shading(const Scene& scene, const CommitOptions& options, const FrameOptions& frame,
                                const PreparedScene& prepared) {
    PreparedShading s;
    s.settings = frame_settings(scene.settings, frame, scene.name);
    s.camera = scene.camera;
    s.camera.position -= prepared.frame_origin;
    s.camera.look_at -= prepared.frame_origin;
    if (options.accuracy.precision == Precision::Float && !prepared.geometry_f.triangles.empty())
        check_float_camera_reach(scene.name, s.camera.position);
    s.materials = scene.materials;
    if (s.materials.empty()) s.materials.push_back(Material{.name = "default"});  // a query-only scene (scene.h)
    s.lights = scene.lights;
    for (PointLight& l : s.lights) l.position -= prepared.frame_origin;
    s.features = options.all_features ? SceneFeatures::all(s.settings.max_depth)
                                      : SceneFeatures::of(scene, s.settings.max_depth);
    return s;
}

void PreparedShading::move_into(PreparedScene& p) && {
    p.settings = settings;
    p.camera = camera;
    p.materials = std::move(materials);
    p.lights = std::move(lights);
    p.features = features;
}

// Object bounds handed to the builders are padded by a small fraction of the
// scene's extent. Traversals compute split-plane crossings in the working
// precision, so a hit lying within rounding error of a split plane may be
// looked for on either side of it, and a cell thinner than that error may be
// stepped over. With padding, every object within the pad of a split plane is
// stored on both sides of it, so whichever side the arithmetic picks holds it.
// 2^-18 of the extent is some 30 float ulps: enough for float traversal of a
// scene seen from up to about 30 times its size away, at the price of a little
// more duplication in the tree. The bounds come from the float geometry; the
// double geometry differs from it by at most half a float ulp of the working
// frame's coordinates (< 2^-24 of the extent), well inside the pad, so one
// tree serves both precisions.
constexpr double kBuildPadding = 1.0 / 262144.0;

Aabb PreparedScene::padded(const Aabb& b) const {
    const glm::dvec3 pad(kBuildPadding * extent);
    return round_outward({b.lo - pad, b.hi + pad});
}

namespace {

// A sphere's box (SceneGeometry's float sphere), before padding.
template <class Sphere>
Aabb sphere_box(const Sphere& s) {
    const glm::dvec3 c(s.center);
    return {c - glm::dvec3(s.radius), c + glm::dvec3(s.radius)};
}

// A triangle's box (SceneGeometry's float triangle), before padding.
template <class Triangle>
Aabb triangle_box(const Triangle& t) {
    Aabb b;
    b.extend(glm::dvec3(t.v0));
    b.extend(glm::dvec3(t.v1));
    b.extend(glm::dvec3(t.v2));
    return b;
}

}  // namespace

Aabb PreparedScene::object_bound(std::uint32_t id) const {
    const auto& g = geometry_f;
    if (id < g.spheres.size()) return padded(sphere_box(g.spheres[id]));
    return padded(triangle_box(g.triangles[id - g.spheres.size()]));
}

Aabb PreparedScene::objects_bound(std::span<const std::uint32_t> ids) const {
    const auto& g = geometry_f;
    const std::size_t spheres = g.spheres.size();
    // A leaf's objects lie apart in the arrays: their loads are started together.
    for (std::uint32_t id : ids)
        if (id >= spheres) {
            const auto* t = &g.triangles[id - spheres];
            __builtin_prefetch(t);
            __builtin_prefetch(reinterpret_cast<const char*>(t + 1) - 1);  // the next line, where it reaches it
        }
    // Triangles' boxes are their float vertices' extremes, exact in float;
    // spheres' are taken in double, as object_bound takes them.
    glm::vec3 lo(std::numeric_limits<float>::infinity()), hi(-std::numeric_limits<float>::infinity());
    Aabb sphere_part;
    for (std::uint32_t id : ids) {
        if (id < spheres) {
            sphere_part.extend(sphere_box(g.spheres[id]));
        } else {
            const auto& t = g.triangles[id - spheres];
            lo = glm::min(lo, glm::min(t.v0, glm::min(t.v1, t.v2)));
            hi = glm::max(hi, glm::max(t.v0, glm::max(t.v1, t.v2)));
        }
    }
    Aabb raw{glm::dvec3(lo), glm::dvec3(hi)};
    raw.extend(sphere_part);
    return raw.empty() ? raw : padded(raw);
}

std::vector<Aabb> PreparedScene::object_bounds() const {
    std::vector<Aabb> out(geometry_f.object_count());
    // In parallel: a big mesh's boxes are a serial 70 ms otherwise.
    auto boxes = [&](const tbb::blocked_range<std::uint32_t>& range) {
        for (std::uint32_t id = range.begin(); id < range.end(); ++id) out[id] = object_bound(id);
    };
    TsanForkJoin tsan;
    tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, geometry_f.object_count(), 16384), tsan.task(boxes));
    return out;
}

namespace {

// The polygon's box; empty for no vertices.
Aabb polygon_box(const ClipPolygon& poly) {
    ClipBox b;
    for (int i = 0; i < poly.n; ++i) b.extend(poly.v[static_cast<std::size_t>(i)]);
    return b.aabb();
}

// A triangle clipped to `box`: only against the planes it crosses (against any
// other, clipping returns it unchanged; a straddler mostly crosses the new split alone).
template <class Triangle>
ClipPolygon clip_triangle(const Triangle& t, const Aabb& box) {
    ClipPolygon buffers[2];
    ClipPolygon* poly = &buffers[0];
    ClipPolygon* next = &buffers[1];
    poly->v[0] = {t.v0.x, t.v0.y, t.v0.z};
    poly->v[1] = {t.v1.x, t.v1.y, t.v1.z};
    poly->v[2] = {t.v2.x, t.v2.y, t.v2.z};
    poly->n = 3;
    for (int a = 0; a < 3 && poly->n > 0; ++a) {
        double lo = poly->v[0][a], hi = lo;
        for (int i = 1; i < poly->n; ++i) {
            lo = std::min(lo, poly->v[static_cast<std::size_t>(i)][a]);
            hi = std::max(hi, poly->v[static_cast<std::size_t>(i)][a]);
        }
        if (lo < box.lo[a]) {
            clip_polygon(*poly, *next, a, box.lo[a], false);
            std::swap(poly, next);
        }
        if (hi > box.hi[a] && poly->n > 0) {
            clip_polygon(*poly, *next, a, box.hi[a], true);
            std::swap(poly, next);
        }
    }
    return *poly;
}

// The box of the polygon's part on one side of a plane (keep_below: at or below it).
Aabb part_box(const ClipPolygon& poly, const Aabb& poly_box, int axis, double plane, bool keep_below) {
    if (keep_below ? poly_box.hi[axis] <= plane : poly_box.lo[axis] >= plane) return poly_box;
    // The part's box straight from its vertices, in the order polygon_box
    // would take them: the same box, without writing the part out.
    ClipBox box;
    clip_polygon_to(poly, axis, plane, keep_below, [&](const ClipPoint& p) { box.extend(p); });
    return box.aabb();
}

}  // namespace

KdBuildInput PreparedScene::build_input() const {
    KdBuildInput in;
    in.bounds = object_bounds();
    const std::uint32_t sphere_count = static_cast<std::uint32_t>(geometry_f.spheres.size());
    in.sphere_count = sphere_count;  // spheres come first: the SAH costs their tests apart
    // The clippers refer to this PreparedScene, which must outlive the build.
    // They clip against the cell grown by the pad, so that perfect splits keep
    // the padding's promise: an object within the pad of a plane is on both sides.
    in.clip = [this, sphere_count](std::uint32_t id, const Aabb& cell) -> Aabb {
        const glm::dvec3 pad(kBuildPadding * extent);
        if (id < sphere_count) return object_bound(id).intersect(cell);
        const ClipPolygon poly = clip_triangle(geometry_f.triangles[id - sphere_count], {cell.lo - pad, cell.hi + pad});
        const Aabb b = polygon_box(poly);
        return b.empty() ? b : padded(b).intersect(cell);
    };
    // Both halves at once: the triangle is clipped to the grown cell once,
    // then that polygon to each half's grown side of the plane.
    in.split = [this, sphere_count](std::uint32_t id, const Aabb& cell, int axis, double pos, Aabb& below,
                                    Aabb& above) {
        const double pad = kBuildPadding * extent;
        if (id < sphere_count) {
            below = above = object_bound(id);
            return;
        }
        const ClipPolygon poly =
            clip_triangle(geometry_f.triangles[id - sphere_count], {cell.lo - glm::dvec3(pad), cell.hi + glm::dvec3(pad)});
        const Aabb box = polygon_box(poly);
        if (box.empty()) {
            below = above = box;
            return;
        }
        below = part_box(poly, box, axis, pos + pad, true);
        above = part_box(poly, box, axis, pos - pad, false);
        if (!below.empty()) below = padded(below);
        if (!above.empty()) above = padded(above);
    };
    return in;
}

}  // namespace kdrt::detail

namespace kdrt {

bool bvh_has_traversal(Traversal t) { return t == Traversal::Stack || t == Traversal::None; }

}  // namespace kdrt
