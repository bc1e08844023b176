#include "render/prepared_scene.h"

#include "common/fnv1a.h"

#include <kdrt/error.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>

namespace kdrt::detail {

namespace {

// Rounds a box outward to float-representable values: a float copy of any
// point inside the double box then lies inside the result.
Aabb round_outward(const Aabb& b) {
    Aabb r;
    for (int a = 0; a < 3; ++a) {
        float lo = static_cast<float>(b.lo[a]);
        float hi = static_cast<float>(b.hi[a]);
        if (static_cast<double>(lo) > b.lo[a]) lo = std::nextafter(lo, -INFINITY);
        if (static_cast<double>(hi) < b.hi[a]) hi = std::nextafter(hi, INFINITY);
        // One more step covers vertices that were themselves rounded to float.
        r.lo[a] = std::nextafter(lo, -INFINITY);
        r.hi[a] = std::nextafter(hi, INFINITY);
    }
    return r;
}

// A convex polygon with room for a triangle clipped by six planes (each
// plane adds at most one vertex): no allocation in the builders' hot loop.
struct ClipPolygon {
    std::array<glm::dvec3, 9> v;
    int n = 0;
};

// Sutherland-Hodgman clipping of a convex polygon against one axis-aligned half-space.
void clip_polygon(const ClipPolygon& poly, ClipPolygon& out, int axis, double value, bool keep_below) {
    out.n = 0;
    auto inside = [&](const glm::dvec3& p) { return keep_below ? p[axis] <= value : p[axis] >= value; };
    for (int i = 0; i < poly.n; ++i) {
        const glm::dvec3& a = poly.v[static_cast<std::size_t>(i)];
        const glm::dvec3& b = poly.v[static_cast<std::size_t>((i + 1) % poly.n)];
        bool ia = inside(a), ib = inside(b);
        if (ia) out.v[static_cast<std::size_t>(out.n++)] = a;
        if (ia != ib) {
            double t = (value - a[axis]) / (b[axis] - a[axis]);
            glm::dvec3 p = a + t * (b - a);
            p[axis] = value;
            out.v[static_cast<std::size_t>(out.n++)] = p;
        }
    }
}

template <class Real>
void fill_geometry(SceneGeometry<Real>& g, const Scene& scene, const glm::dvec3& origin) {
    using Vec = glm::vec<3, Real>;
    auto local = [&](const glm::dvec3& p) { return Vec(p - origin); };
    g.spheres.reserve(scene.spheres.size());
    for (const Sphere& s : scene.spheres)
        g.spheres.push_back({local(s.center), static_cast<Real>(s.radius), s.material});
    g.triangles.reserve(scene.triangle_count());
    auto add_mesh = [&](const Mesh& mesh) {
        for (const MeshTriangle& t : mesh.triangles) {
            typename SceneGeometry<Real>::TriangleData d{local(mesh.positions[t.v[0]]), local(mesh.positions[t.v[1]]),
                                                         local(mesh.positions[t.v[2]]), t.material, kNoNormal};
            if (t.n[0] != kNoNormal && t.n[1] != kNoNormal && t.n[2] != kNoNormal) {
                d.normals = static_cast<std::uint32_t>(g.normals.size());
                for (std::uint32_t n : t.n) g.normals.push_back(Vec(glm::normalize(mesh.normals[n])));
            }
            g.triangles.push_back(d);
        }
    };
    add_mesh(scene.triangles);
    for (const Mesh& m : scene.meshes) add_mesh(m);
}

}  // namespace

PreparedScene prepare_scene(const Scene& scene, const RenderOptions& options) {
    validate(scene);
    PreparedScene p;
    p.settings = scene.settings;
    if (options.width < 0 || options.height < 0 || options.max_depth < 0 || options.samples < 0)
        throw Error(ErrorCode::InvalidArgument, "width, height, max_depth and samples must not be negative");
    if (options.width) p.settings.width = options.width;
    if (options.height) p.settings.height = options.height;
    if (options.max_depth) p.settings.max_depth = options.max_depth;
    if (options.samples) p.settings.samples = options.samples;
    if (p.settings.width > 16384 || p.settings.height > 16384)
        throw Error(ErrorCode::InvalidArgument, "image size must be at most 16384 x 16384");
    if (p.settings.samples > 4096) throw Error(ErrorCode::InvalidArgument, "samples must be at most 4096");
    if (p.settings.max_depth > KDRT_MAX_RAY_DEPTH)
        throw Error(ErrorCode::InvalidArgument, "max_depth must be at most " + std::to_string(KDRT_MAX_RAY_DEPTH));
    if (!(std::isfinite(options.fixed_epsilon) && options.fixed_epsilon > 0.0))
        throw Error(ErrorCode::InvalidArgument, "fixed_epsilon must be a positive finite number");

    // World-space bounds of all objects decide the working frame.
    Aabb world;
    for (const Sphere& s : scene.spheres) {
        world.extend(s.center - glm::dvec3(s.radius));
        world.extend(s.center + glm::dvec3(s.radius));
    }
    auto extend_mesh = [&](const Mesh& m) {
        for (const MeshTriangle& t : m.triangles)
            for (std::uint32_t v : t.v) world.extend(m.positions[v]);
    };
    extend_mesh(scene.triangles);
    for (const Mesh& m : scene.meshes) extend_mesh(m);
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
            throw Error(ErrorCode::InvalidScene, "the scene's objects span " + std::to_string(p.extent) +
                                                     " units, more than the float range kdrt works in (1e30)");
    }

    p.camera = scene.camera;
    p.camera.position -= p.frame_origin;
    p.camera.look_at -= p.frame_origin;
    p.materials = scene.materials;
    p.lights = scene.lights;
    for (PointLight& l : p.lights) l.position -= p.frame_origin;
    p.features = options.all_features ? SceneFeatures::all(p.settings.max_depth)
                                      : SceneFeatures::of(scene, p.settings.max_depth);

    fill_geometry(p.geometry_d, scene, p.frame_origin);
    fill_geometry(p.geometry_f, scene, p.frame_origin);

    std::uint64_t h = kFnv1aOffsetBasis;
    for (const auto& s : p.geometry_f.spheres) {
        h = fnv1a(h, &s.center, sizeof(s.center));
        h = fnv1a(h, &s.radius, sizeof(s.radius));
    }
    for (const auto& t : p.geometry_f.triangles) {
        h = fnv1a(h, &t.v0, sizeof(t.v0));
        h = fnv1a(h, &t.v1, sizeof(t.v1));
        h = fnv1a(h, &t.v2, sizeof(t.v2));
    }
    std::uint64_t counts[2] = {p.geometry_f.spheres.size(), p.geometry_f.triangles.size()};
    p.fingerprint = fnv1a(h, counts, sizeof(counts));
    return p;
}

// Object bounds handed to the builders are padded by a small fraction of the
// scene's extent. Traversals compute split-plane crossings in the working
// precision, so a hit lying within rounding error of a split plane may be
// looked for on either side of it, and a cell thinner than that error may be
// stepped over. With padding, every object within the pad of a split plane is
// stored on both sides of it, so whichever side the arithmetic picks holds it.
// 2^-18 of the extent is some 30 float ulps: enough for float traversal of a
// scene seen from up to about 30 times its size away, at the price of a little
// more duplication in the tree.
constexpr double kBuildPadding = 1.0 / 262144.0;

Aabb PreparedScene::padded(const Aabb& b) const {
    const glm::dvec3 pad(kBuildPadding * extent);
    return round_outward({b.lo - pad, b.hi + pad});
}

KdBuildInput PreparedScene::build_input() const {
    KdBuildInput in;
    const auto& g = geometry_d;
    in.bounds.reserve(g.object_count());
    for (const auto& s : g.spheres)
        in.bounds.push_back(padded({s.center - glm::dvec3(s.radius), s.center + glm::dvec3(s.radius)}));
    for (const auto& t : g.triangles) {
        Aabb b;
        b.extend(t.v0);
        b.extend(t.v1);
        b.extend(t.v2);
        in.bounds.push_back(padded(b));
    }
    const std::uint32_t sphere_count = static_cast<std::uint32_t>(g.spheres.size());
    in.sphere_count = sphere_count;  // spheres come first: the SAH costs their tests apart
    // The clipper refers to this PreparedScene, which must outlive the build.
    // It clips against the cell grown by the pad, so that perfect splits keep
    // the padding's promise: an object within the pad of a plane is on both sides.
    in.clip = [this, sphere_count](std::uint32_t id, const Aabb& cell) -> Aabb {
        const glm::dvec3 pad(kBuildPadding * extent);
        const Aabb grown{cell.lo - pad, cell.hi + pad};
        if (id < sphere_count) {
            const auto& s = geometry_d.spheres[id];
            return padded({s.center - glm::dvec3(s.radius), s.center + glm::dvec3(s.radius)}).intersect(cell);
        }
        const auto& t = geometry_d.triangles[id - sphere_count];
        ClipPolygon poly, next;
        poly.v[0] = t.v0;
        poly.v[1] = t.v1;
        poly.v[2] = t.v2;
        poly.n = 3;
        for (int a = 0; a < 3 && poly.n > 0; ++a) {
            clip_polygon(poly, next, a, grown.lo[a], false);
            clip_polygon(next, poly, a, grown.hi[a], true);
        }
        Aabb b;
        for (int i = 0; i < poly.n; ++i) b.extend(poly.v[static_cast<std::size_t>(i)]);
        if (b.empty()) return b;
        return padded(b).intersect(cell);
    };
    return in;
}

}  // namespace kdrt::detail
