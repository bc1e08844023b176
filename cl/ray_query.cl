/* ray_query.cl: the ray queries of kdrt/ray_query.h, QueryRay[] -> QueryHit[]
 * (closest hit) or uchar[] (any hit), on the traversal the program was built
 * for, with the same setup as the C++ devices' queries (keep them in step).
 *
 * A query ray is in world space with any direction length and hits on
 * (max(t_min, 0), t_max] in units of that direction. As on the host
 * (src/cpu/ray_queries.cpp), it is moved into the working frame (origin minus
 * frame_origin and the direction's normalisation in double, rounded once),
 * and the window is applied to t / |direction|. The intersection tests take
 * t > 0 only, so for t_min > 0 the origin is advanced to t_min instead of
 * testing both sphere roots against the window: the same hits, with t
 * rounded differently near t_min. Every walk's bound lies a little beyond
 * the window's end, so that no rounding of a split plane or box loses a hit
 * inside; an any-hit walk stopped by a hit past the end is answered by the
 * closest hit (stopped_past_end). A ray with a non-finite component, a zero
 * direction, a NaN bound or t_min > t_max hits nothing. */

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
#ifdef KDRT_PACKETS
/* query_origin of four queries, lane k being q[k]'s: x, y and z. */
inline void query_origins4(const QueryRay* q, double4 frame_origin, real4* o) {
    for (int a = 0; a < 3; ++a) {
        const double4 w = (double4)(q[0].origin[a], q[1].origin[a], q[2].origin[a], q[3].origin[a]);
        o[a] = convert_real4(w - (a == 0 ? frame_origin.x : a == 1 ? frame_origin.y : frame_origin.z));
    }
}
#endif
#else
#define KDRT_FRAME_PARAMS float4 frame_hi, float4 frame_lo
#define KDRT_FRAME_ARGS frame_hi, frame_lo
inline real3 query_origin(const QueryRay* q, float4 hi, float4 lo) {
    return (real3)((q->origin[0] - hi.x) - lo.x, (q->origin[1] - hi.y) - lo.y, (q->origin[2] - hi.z) - lo.z);
}
#ifdef KDRT_PACKETS
inline void query_origins4(const QueryRay* q, float4 hi, float4 lo, real4* o) {
    for (int a = 0; a < 3; ++a) {
        const float4 w = (float4)(q[0].origin[a], q[1].origin[a], q[2].origin[a], q[3].origin[a]);
        o[a] = (w - (a == 0 ? hi.x : a == 1 ? hi.y : hi.z)) - (a == 0 ? lo.x : a == 1 ? lo.y : lo.z);
    }
}
#endif
#endif

/* The window's arithmetic, in double where the device has it (as the host). */
#ifdef KDRT_HAS_FP64
typedef double qreal;
typedef double3 qreal3;
#ifdef KDRT_PACKETS
typedef double4 qreal4;
#define convert_qreal4 convert_double4
#define qreal_lane_bits(m) int_lane_bits(convert_int4(m))
#endif
#else
typedef float qreal;
typedef float3 qreal3;
#ifdef KDRT_PACKETS
typedef float4 qreal4;
#define convert_qreal4 convert_float4
#define qreal_lane_bits(m) int_lane_bits(m)
#endif
#endif

#ifdef KDRT_DOUBLE
#define KDRT_REAL_MAX DBL_MAX
#else
#define KDRT_REAL_MAX FLT_MAX
#endif

/* A query's window and the scale between its units and the working ray's.
 * The working ray is kept apart, written by setup_query where the walk reads
 * it: a copy out of the setup would be read back before its stores landed. */
typedef struct QuerySetup {
    real bound;        /* the traversal's: a little beyond the window's end */
    qreal shift;       /* how far the origin was advanced (t_min > 0), in unit-direction units */
    qreal len;         /* the query direction's length */
    qreal t_min, t_max;
} QuerySetup;

/* A working ray's t in the query's units. */
inline qreal query_t(const QuerySetup* s, real t) {
    return ((qreal)t + s->shift) / s->len;
}

/* How far to advance the origin for a window starting at t_min > 0: t_min * len,
 * raised by ulps until every t > 0 is past t_min in the query's units. */
inline void set_window_shift(QuerySetup* s) {
    s->shift = s->t_min * s->len;
    for (int k = 0; k < 8 && !(query_t(s, nextafter(R(0), R(1))) > s->t_min); ++k)
        s->shift = nextafter(s->shift, (qreal)INFINITY);
}

inline bool setup_query(QueryRay q, real3 org, QuerySetup* s, Ray* ray) {
    const qreal3 d = (qreal3)(q.direction[0], q.direction[1], q.direction[2]);
    if (!isfinite(d.x) || !isfinite(d.y) || !isfinite(d.z)) return false;
    if (!isfinite(org.x) || !isfinite(org.y) || !isfinite(org.z)) return false;
    if (isnan(q.t_min) || isnan(q.t_max) || q.t_min > q.t_max) return false;
    s->len = sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    if (!(s->len > 0) || !isfinite(s->len)) return false;
    const qreal3 unit = d / s->len;
    const real3 dir = (real3)((real)unit.x, (real)unit.y, (real)unit.z);
    if (dir.x == R(0) && dir.y == R(0) && dir.z == R(0)) return false;
    s->t_min = q.t_min;
    s->t_max = q.t_max;
    s->shift = 0;
    if (q.t_min > 0.0f) {
        set_window_shift(s);
        org = org + (real)s->shift * dir;
    }
    /* Beyond the window's end by a millionth of its distance from the query's
     * origin: more than the rounding of that distance minus the shift. */
    const qreal bound = s->t_max * s->len * (qreal)(1.0 + 1e-6) - s->shift;
    s->bound = bound < (qreal)KDRT_REAL_MAX ? (real)bound : REAL_INF;
    *ray = make_ray(org, dir, KDRT_NONE_ID);
    return true;
}

/* A hit at t (of the working ray) is inside the window, in the query's units.
 * Every t > 0 is past t_min: for t_min > 0 by set_window_shift, for t_min <= 0
 * also where t / len rounds to 0. */
inline bool in_window(const QuerySetup* s, real t, qreal* t_query) {
    *t_query = query_t(s, t);
    return t > R(0) && (s->t_min <= 0 || *t_query > s->t_min) && *t_query <= s->t_max;
}

/* The store_* functions write each field straight into the result: a
 * QueryHit built aside and copied would be read back before its stores landed. */
inline void store_no_hit(__global QueryHit* out) {
    out->t = INFINITY;
    out->normal[0] = out->normal[1] = out->normal[2] = 0.0f;
    out->u = out->v = 0.0f;
    out->object = out->geometry = out->primitive = KDRT_NO_HIT;
    out->kind = KDRT_KIND_NONE;
}

/* The QueryHit of object `id` hit at t_query (the query's units; t: the
 * working ray's), with barycentrics b1, b2 on a triangle, into *out. With an
 * id map (map_ids), object i is named by id_map[3i .. 3i+2]: object,
 * geometry, primitive; without, by its internal id (geometry = id,
 * primitive 0), which the host maps. */
inline void store_query_hit(__global QueryHit* out, const Scene* scene, const Ray* ray, uint id, real t,
                            qreal t_query, real b1, real b2, __global const uint* id_map, uint map_ids) {
    real3 n;
    if (id < scene->sphere_count) {
        __global const SphereRec* sp = &scene->spheres[id];
        n = normalize3(ray->org + t * ray->dir - load3(sp->center));
        out->kind = KDRT_KIND_SPHERE;
        out->u = out->v = 0.0f;
    } else {
        __global const TriangleRec* tri = &scene->triangles[id - scene->sphere_count];
        const real3 v0 = load3(tri->v0);
        n = normalize3(cross3(load3(tri->v1) - v0, load3(tri->v2) - v0));
        out->kind = KDRT_KIND_TRIANGLE;
        out->u = (float)b1;
        out->v = (float)b2;
    }
    out->t = (float)t_query;
    out->object = map_ids ? id_map[3 * id] : id;
    out->geometry = map_ids ? id_map[3 * id + 1] : id;
    out->primitive = map_ids ? id_map[3 * id + 2] : 0u;
    out->normal[0] = (float)n.x;
    out->normal[1] = (float)n.y;
    out->normal[2] = (float)n.z;
}

/* The record of a hit object, which store_query_hit reads: the leaves'
 * packed copies were tested, so it is seldom in cache. */
inline void prefetch_hit_object(const Scene* scene, Hit h) {
    if (h.id == KDRT_NONE_ID) return;
    const uint id = (uint)h.id;
    if (id < scene->sphere_count)
        KDRT_PREFETCH(&scene->spheres[id]);
    else
        prefetch_lines((__global const uchar*)&scene->triangles[id - scene->sphere_count], (uint)sizeof(TriangleRec));
}

/* The QueryHit of a query whose working ray's closest hit is h (none outside the window). */
inline void store_closest_hit(__global QueryHit* out, const Scene* scene, const QuerySetup* s, const Ray* ray, Hit h,
                              __global const uint* id_map, uint map_ids) {
    qreal t;
    if (h.id == KDRT_NONE_ID || !in_window(s, h.t, &t))
        store_no_hit(out);
    else
        store_query_hit(out, scene, ray, (uint)h.id, h.t, t, h.b1, h.b2, id_map, map_ids);
}

#ifdef KDRT_PACKETS
#if KDRT_PACKETS != 4
#error "setup_queries4 sets up packets of four queries"
#endif
/* setup_query of four queries q[0..3] at once, into s[k] and ray[k], lane k
 * of each vector being query k: the same IEEE operations lane by lane
 * (FP_CONTRACT is off), so the same bits, with the four square roots and
 * divisions in flight together. A query the vectors leave out (one that
 * fails a check, or t_min > 0, whose origin moves) takes setup_query.
 * Returns the queries set up (bit k: q[k]); the others' s[k] and ray[k] are
 * not to be read. */
inline uint setup_queries4(const QueryRay* q, KDRT_FRAME_PARAMS, QuerySetup* s, Ray* ray) {
    float4 d[3];
    for (int a = 0; a < 3; ++a)
        d[a] = (float4)(q[0].direction[a], q[1].direction[a], q[2].direction[a], q[3].direction[a]);
    const float4 t_min = (float4)(q[0].t_min, q[1].t_min, q[2].t_min, q[3].t_min);
    const float4 t_max = (float4)(q[0].t_max, q[1].t_max, q[2].t_max, q[3].t_max);
    const qreal4 dx = convert_qreal4(d[0]), dy = convert_qreal4(d[1]), dz = convert_qreal4(d[2]);
    const qreal4 len = sqrt(dx * dx + dy * dy + dz * dz);
    const real4 u[3] = {convert_real4(dx / len), convert_real4(dy / len), convert_real4(dz / len)};
    real4 org[3];
    query_origins4(q, KDRT_FRAME_ARGS, org);
    make_rays4(org, u, KDRT_NONE_ID, ray);
    /* setup_query's checks, and t_min <= 0: the shift is 0, so leaving out its
     * subtraction from the bound changes no bits */
    uint simple = int_lane_bits(isfinite(d[0]) & isfinite(d[1]) & isfinite(d[2]) & (t_min <= 0.0f) & (t_min <= t_max));
    simple &= qreal_lane_bits((len > (qreal)0) & isfinite(len));
    simple &= lane_bits(isfinite(org[0]) & isfinite(org[1]) & isfinite(org[2]) &
                        ((u[0] != R(0)) | (u[1] != R(0)) | (u[2] != R(0))));
    qreal lens[4], bounds[4];
    vstore4(len, 0, lens);
    vstore4(convert_qreal4(t_max) * len * (qreal)(1.0 + 1e-6), 0, bounds);
    uint valid = simple;
    for (uint k = 0; k < 4u; ++k) {
        if (((simple >> k) & 1u) == 0u) {
            if (setup_query(q[k], query_origin(&q[k], KDRT_FRAME_ARGS), &s[k], &ray[k])) valid |= 1u << k;
            continue;
        }
        s[k].len = lens[k];
        s[k].t_min = q[k].t_min;
        s[k].t_max = q[k].t_max;
        s[k].shift = 0;
        s[k].bound = bounds[k] < (qreal)KDRT_REAL_MAX ? (real)bounds[k] : REAL_INF;
    }
    return valid;
}

/* A CPU device's work-item takes KDRT_PACKETS consecutive queries, traced
 * as a packet where they can be (trace_lanes): each gets its setup s[k], its
 * working ray ray[k] and traverse()'s hit h[k] (a query whose setup failed:
 * no hit, and its s[k] and ray[k] are not to be read). Returns how many (0:
 * none left), from index *at of the buffers on. */
inline uint query_lanes(const Scene* scene, __global const QueryRay* rays, uint first, uint count,
                        KDRT_FRAME_PARAMS, bool any_hit, QuerySetup* s, Ray* ray, Hit* h, uint* at) {
    const uint i0 = (uint)get_global_id(0) * KDRT_PACKETS;
    *at = first + i0;
    if (i0 >= count) return 0u;
    const uint n = min(count - i0, (uint)KDRT_PACKETS);
    real bound[KDRT_PACKETS];
    uint valid = 0u;
    if (n == KDRT_PACKETS) {
        QueryRay q[KDRT_PACKETS];
        for (uint k = 0; k < n; ++k) q[k] = rays[*at + k];
        valid = setup_queries4(q, KDRT_FRAME_ARGS, s, ray);
    } else {
        for (uint k = 0; k < n; ++k) {
            const QueryRay q = rays[*at + k];
            if (setup_query(q, query_origin(&q, KDRT_FRAME_ARGS), &s[k], &ray[k])) valid |= 1u << k;
        }
    }
    for (uint k = 0; k < n; ++k) {
        h[k] = no_hit();
        if (((valid >> k) & 1u) != 0u) bound[k] = s[k].bound;
    }
    trace_lanes(scene, ray, valid, bound, any_hit, h);
    return n;
}
#endif

/* The closest hit does not depend on the order of the tests (closer_than
 * breaks ties): the packed leaves give the same one, as for renders. */
__kernel void query_closest(KDRT_SCENE_PARAMS, __global const QueryRay* rays, __global QueryHit* hits, uint first,
                            uint count, KDRT_FRAME_PARAMS, __global const uint* id_map, uint map_ids) {
    const Scene scene = make_scene(KDRT_SCENE_ARGS, true);
#ifdef KDRT_PACKETS
    QuerySetup s[KDRT_PACKETS];
    Ray ray[KDRT_PACKETS];
    Hit h[KDRT_PACKETS];
    uint at;
    const uint n = query_lanes(&scene, rays, first, count, KDRT_FRAME_ARGS, false, s, ray, h, &at);
    for (uint k = 0; k < n; ++k) prefetch_hit_object(&scene, h[k]); /* the lanes' misses overlap */
    for (uint k = 0; k < n; ++k) store_closest_hit(&hits[at + k], &scene, &s[k], &ray[k], h[k], id_map, map_ids);
#else
    const uint i = get_global_id(0);
    if (i >= count) return;
    const QueryRay q = rays[first + i];
    QuerySetup s;
    Ray ray;
    Hit h = no_hit();
    if (setup_query(q, query_origin(&q, KDRT_FRAME_ARGS), &s, &ray)) traverse(&scene, &ray, s.bound, false, &h);
    store_closest_hit(&hits[first + i], &scene, &s, &ray, h, id_map, map_ids);
#endif
}

/* Whether a walk's hit h is inside the window: the query's answer where h
 * is the closest hit, or the hit that stopped an any-hit walk. */
inline uchar hit_inside(const QuerySetup* s, Hit h) {
    qreal t;
    return h.id != KDRT_NONE_ID && in_window(s, h.t, &t) ? 1 : 0;
}

/* Whether an any-hit walk stopped at a hit past the window's end, within the
 * bound's slack: it may have stopped before a hit inside, so the closest hit
 * answers instead, which is inside exactly when some hit is (every t > 0 is
 * past t_min, in_window). A walk that did not stop holds no hit below the
 * bound: none inside. So the answer does not depend on the order of the
 * tests, and the walk takes the packed leaves too. A walk without a hit
 * (also a query whose setup failed, whose s is not read) did not stop. */
inline bool stopped_past_end(const QuerySetup* s, Hit h) {
    return h.id != KDRT_NONE_ID && h.t < s->bound && !hit_inside(s, h);
}

__kernel void query_any(KDRT_SCENE_PARAMS, __global const QueryRay* rays, __global uchar* occluded, uint first,
                        uint count, KDRT_FRAME_PARAMS) {
    const Scene scene = make_scene(KDRT_SCENE_ARGS, true);
#ifdef KDRT_PACKETS
    QuerySetup s[KDRT_PACKETS];
    Ray ray[KDRT_PACKETS];
    Hit h[KDRT_PACKETS];
    uint at;
    const uint n = query_lanes(&scene, rays, first, count, KDRT_FRAME_ARGS, true, s, ray, h, &at);
    for (uint k = 0; k < n; ++k) {
        if (stopped_past_end(&s[k], h[k])) {
            h[k] = no_hit();
            traverse(&scene, &ray[k], s[k].bound, false, &h[k]);
        }
        occluded[at + k] = hit_inside(&s[k], h[k]);
    }
#else
    const uint i = get_global_id(0);
    if (i >= count) return;
    const QueryRay q = rays[first + i];
    uchar blocked = 0;
    QuerySetup s;
    Ray ray;
    if (setup_query(q, query_origin(&q, KDRT_FRAME_ARGS), &s, &ray)) {
        /* The any-hit walk, and the closest-hit one where it stopped past the
         * end, through one call of traverse (which a GPU inlines). */
        Hit h = no_hit();
        for (bool any_hit = true;; any_hit = false) {
            traverse(&scene, &ray, s.bound, any_hit, &h);
            if (!any_hit || !stopped_past_end(&s, h)) break;
            h = no_hit();
        }
        blocked = hit_inside(&s, h);
    }
    occluded[first + i] = blocked;
#endif
}
