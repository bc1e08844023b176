/* ray_query.cl: the ray queries of kdrt/ray_query.h, QueryRay[] -> QueryHit[]
 * (closest hit) or uchar[] (any hit), on the traversal the program was built
 * for, with the same setup as the C++ devices' queries (keep them in step).
 *
 * A query ray is in world space with any direction length and hits on
 * (t_min, t_max] in units of that direction. It is moved into the working
 * frame (origin minus frame_origin, rounded once), its direction normalised,
 * and for t_min > 0 its origin advanced to t_min, so the intersection tests
 * (which take t > 0) see exactly the window. A ray with a zero or non-finite
 * direction, a non-finite origin or an empty window hits nothing. */

/* The working frame's world-space origin: in double where the device has it
 * (the subtraction then rounds once, as on the host), else as a float pair
 * hi + lo. */
#ifdef KDRT_HAS_FP64
#define KDRT_FRAME_PARAMS double4 frame_origin
#define KDRT_FRAME_ARGS frame_origin
inline real3 query_origin(const QueryRay* q, double4 frame_origin) {
    return (real3)((real)((double)q->origin[0] - frame_origin.x), (real)((double)q->origin[1] - frame_origin.y),
                   (real)((double)q->origin[2] - frame_origin.z));
}
#else
#define KDRT_FRAME_PARAMS float4 frame_hi, float4 frame_lo
#define KDRT_FRAME_ARGS frame_hi, frame_lo
inline real3 query_origin(const QueryRay* q, float4 hi, float4 lo) {
    return (real3)((q->origin[0] - hi.x) - lo.x, (q->origin[1] - hi.y) - lo.y, (q->origin[2] - hi.z) - lo.z);
}
#endif

typedef struct QuerySetup {
    Ray ray;
    real t_max; /* of the working ray */
    real shift; /* how far the origin was advanced (t_min, normalised) */
    real len;   /* the query direction's length */
} QuerySetup;

inline bool setup_query(QueryRay q, real3 org, QuerySetup* s) {
    const real3 d = (real3)((real)q.direction[0], (real)q.direction[1], (real)q.direction[2]);
    s->len = sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    if (!(s->len > R(0)) || !isfinite(s->len)) return false;
    if (!isfinite(org.x) || !isfinite(org.y) || !isfinite(org.z)) return false;
    const real3 dir = d / s->len;
    const real t_min = q.t_min > 0.0f ? (real)q.t_min * s->len : R(0);
    const real t_max = (real)q.t_max * s->len;
    if (!(t_max > t_min)) return false; /* empty window, or NaN */
    s->shift = t_min;
    s->t_max = t_max;
    if (t_min > R(0)) {
        org = org + t_min * dir;
        s->t_max = t_max - t_min;
    }
    s->ray = make_ray(org, dir, KDRT_NONE_ID);
    return true;
}

inline void set_no_hit(QueryHit* out) {
    out->t = INFINITY;
    out->object = KDRT_NO_HIT;
    out->kind = KDRT_KIND_NONE;
    out->u = out->v = 0.0f;
    out->normal[0] = out->normal[1] = out->normal[2] = 0.0f;
}

__kernel void query_closest(KDRT_SCENE_PARAMS, __global const QueryRay* rays, __global QueryHit* hits, uint first,
                            uint count, KDRT_FRAME_PARAMS, __global const uint* id_map, uint map_ids) {
    const uint i = get_global_id(0);
    if (i >= count) return;
    const Scene scene = make_scene(spheres, triangles, normals, materials, lights, nodes, leaves, leaf_objects, ropes, info);
    const QueryRay q = rays[first + i];
    QueryHit out;
    set_no_hit(&out);
    QuerySetup s;
    if (setup_query(q, query_origin(&q, KDRT_FRAME_ARGS), &s)) {
        Hit h = no_hit();
        traverse(&scene, &s.ray, s.t_max, false, &h);
        if (h.id != KDRT_NONE_ID && h.t <= s.t_max) {
            const uint id = (uint)h.id;
            real3 n;
            if (id < scene.sphere_count) {
                __global const SphereRec* sp = &scene.spheres[id];
                n = normalize(s.ray.org + h.t * s.ray.dir - load3(sp->center));
                out.kind = KDRT_KIND_SPHERE;
            } else {
                __global const TriangleRec* tri = &scene.triangles[id - scene.sphere_count];
                const real3 v0 = load3(tri->v0);
                n = normalize(cross(load3(tri->v1) - v0, load3(tri->v2) - v0));
                out.kind = KDRT_KIND_TRIANGLE;
                out.u = (float)h.b1;
                out.v = (float)h.b2;
            }
            out.t = (float)((h.t + s.shift) / s.len);
            out.object = map_ids ? id_map[id] : id;
            out.normal[0] = (float)n.x;
            out.normal[1] = (float)n.y;
            out.normal[2] = (float)n.z;
        }
    }
    hits[first + i] = out;
}

__kernel void query_any(KDRT_SCENE_PARAMS, __global const QueryRay* rays, __global uchar* occluded, uint first,
                        uint count, KDRT_FRAME_PARAMS) {
    const uint i = get_global_id(0);
    if (i >= count) return;
    const Scene scene = make_scene(spheres, triangles, normals, materials, lights, nodes, leaves, leaf_objects, ropes, info);
    const QueryRay q = rays[first + i];
    uchar blocked = 0;
    QuerySetup s;
    if (setup_query(q, query_origin(&q, KDRT_FRAME_ARGS), &s)) {
        Hit h = no_hit();
        traverse(&scene, &s.ray, s.t_max, true, &h);
        blocked = h.id != KDRT_NONE_ID && h.t <= s.t_max ? 1 : 0;
    }
    occluded[first + i] = blocked;
}
