/* shade.cl: FORMAT.md's Whitted shading for one ray of a bounce, the twin of
 * WhittedTracer in libkdrt/src/cpu/whitted_tracer.h. Instead of
 * recursing, mirror and refracted rays go to the next bounce's queue with
 * their weight; the local colour (times the weight) is returned for the
 * caller to add to the ray's pixel. */

inline Hit closest_hit(const Scene* scene, const Ray* ray) {
    Hit h = no_hit();
    traverse(scene, ray, REAL_INF, false, &h);
    return h;
}

#ifdef KDRT_HAS_LIGHTS
/* Whether a shadow ray's any-hit answer blocks the light t_max away. */
inline bool blocks(Hit h, real t_max) { return h.id != KDRT_NONE_ID && h.t < t_max; }

inline bool occluded(const Scene* scene, const Ray* ray, real t_max) {
    Hit h = no_hit();
    traverse(scene, ray, t_max, true, &h);
    return blocks(h, t_max);
}
#endif

typedef struct Surface {
    real3 p, ng, ns;
    real magnitude;
    bool inside;
    uint material;
} Surface;

/* Hit point rebuilt from the object (see libkdrt/src/cpu/surface.h). */
inline Surface make_surface(const Scene* scene, const Ray* ray, Hit hit) {
    Surface s;
#ifdef KDRT_HAS_SPHERES
    if ((uint)hit.id < scene->sphere_count) {
        __global const SphereRec* sp = &scene->spheres[hit.id];
        const real3 c = load3(sp->center);
        const real3 p = ray->org + hit.t * ray->dir;
        s.ng = normalize3(p - c);
        s.p = c + sp->radius * s.ng;
        s.ns = s.ng;
        const real3 ac = fabs(c);
        s.magnitude = fmax(fmax(ac.x, ac.y), ac.z) + sp->radius;
        s.material = sp->material;
    } else
#endif
    {
#ifdef KDRT_HAS_TRIANGLES
        __global const TriangleRec* tri = &scene->triangles[(uint)hit.id - scene->sphere_count];
        const real3 v0 = load3(tri->v0), v1 = load3(tri->v1), v2 = load3(tri->v2);
        const real b0 = R(1) - hit.b1 - hit.b2;
        s.p = b0 * v0 + hit.b1 * v1 + hit.b2 * v2;
        s.ng = normalize3(cross3(v1 - v0, v2 - v0));
        s.ns = s.ng;
#ifdef KDRT_HAS_NORMALS
        if (tri->normals != KDRT_NO_NORMALS) {
            __global const real* n = scene->normals + 3u * tri->normals;
            const real3 ns = b0 * load3(n) + hit.b1 * load3(n + 3) + hit.b2 * load3(n + 6);
            if (dot3(ns, ns) > R(1e-12)) s.ns = normalize3(ns); /* cancelling normals: keep ng */
        }
#endif
        const real3 m = fmax(fmax(fabs(v0), fabs(v1)), fabs(v2));
        s.magnitude = fmax(fmax(m.x, m.y), m.z);
        /* A huge triangle seen close up: the ray's point, as in surface.h. */
        const real3 ao = fabs(ray->org);
        const real ray_magnitude = fmax(fmax(ao.x, ao.y), ao.z) + hit.t;
        if (R(256) * ray_magnitude < s.magnitude) {
            s.p = ray->org + hit.t * ray->dir;
            s.magnitude = ray_magnitude;
        }
        s.material = tri->material;
#endif
    }
    s.inside = dot3(ray->dir, s.ng) > R(0);
    if (s.inside) {
        s.ng = -s.ng;
        s.ns = -s.ns;
    }
    /* FORMAT.md step 2: vertex normals that disagree with the winding are
     * turned to the geometric normal's side. */
    if (dot3(s.ns, s.ng) < R(0)) s.ns = -s.ns;
    return s;
}

/* x^n for x in [0, 1] and n >= 0 as exp2(n log2 x): pow() is exact to an
 * ulp or two for every x and n, and PoCL's takes several times longer (an
 * extended-precision log and exp); a highlight needs no such care (the images
 * stay within the C++ reference's bound). */
inline real specular_power(real x, real n) {
    return x > R(0) ? exp2(n * log2(x)) : (n == R(0) ? R(1) : R(0));
}

/* KDRT_FIXED_EPSILON (accuracy knob): an absolute offset and no
 * self-exclusion, what breaks when a scene is scaled. */
#ifdef KDRT_FIXED_EPSILON
#define LEAVING(id) KDRT_NONE_ID
#else
#define LEAVING(id) (id)
#endif

inline real3 offset_origin(const Surface* s, real3 dir) {
#ifdef KDRT_FIXED_EPSILON
    const real eps = R(KDRT_FIXED_EPSILON);
#else
    const real eps = KDRT_OFFSET_REL * s->magnitude; /* a few dozen ulps of the object's size */
#endif
    return dot3(dir, s->ng) >= R(0) ? s->p + eps * s->ng : s->p - eps * s->ng;
}

/* Whether two rays of one pixel can be in the same launch: only bounces of a
 * scene whose hits spawn two rays (mirror and glass). Camera rays are one per
 * pixel per launch, and so is every bounce when a hit spawns at most one ray. */
#if defined(KDRT_HAS_REFLECTION) && defined(KDRT_HAS_REFRACTION)
#define KDRT_PIXEL_SHARED(depth) ((depth) > 1u)
#else
#define KDRT_PIXEL_SHARED(depth) false
#endif

/* atomic_add_fixed's sum where no other work-item can touch the pixel. */
inline void add_fixed(__global uint* p, long value) {
    const uint lo = (uint)value, hi = (uint)((ulong)value >> 32);
    const uint old = p[0];
    p[0] = old + lo;
    p[1] += hi + ((uint)(old + lo) < old ? 1u : 0u);
}

/* A colour as the accumulator's three fixed-point values. */
inline long3 fixed_colour(real3 c) {
    const real one = R(KDRT_ACCUM_ONE);
    return (long3)(fixed_from_real(c.x * one), fixed_from_real(c.y * one), fixed_from_real(c.z * one));
}

/* A pixel's fixed-point sum as the image's float: one rounding, as the
 * host's sum -> double -> float gives for any sum below 2^53 (a pixel value
 * below 2^21). */
inline float resolved_value(long sum) { return convert_float_rte(sum) * 0x1p-32f; }
inline float3 resolved_colour(long3 sum) {
    return (float3)(resolved_value(sum.x), resolved_value(sum.y), resolved_value(sum.z));
}

/* accum: per pixel three 64-bit fixed-point sums, as six uints (common.cl).
 * Plain adds where the pixel is this work-item's alone: the same sums, and
 * on a CPU six atomics cost a sizeable share of the shading. */
inline void add_fixed_to_pixel(__global uint* accum, uint pixel, long3 c, bool shared) {
    __global uint* p = accum + 6u * pixel;
    if (!shared) {
        add_fixed(p, c.x);
        add_fixed(p + 2u, c.y);
        add_fixed(p + 4u, c.z);
        return;
    }
    atomic_add_fixed(p, c.x);
    atomic_add_fixed(p + 2u, c.y);
    atomic_add_fixed(p + 4u, c.z);
}

/* The rays a hit spawns for the next bounce, kept by the work-item until the
 * kernel appends them: ray[0] the mirror ray (bit 0 of mask), ray[1] the
 * refracted one (bit 1). Fixed slots keep the indexing static (registers on
 * a GPU). Appending once per work-group instead of once per ray spares the
 * queue's counter, which every thread otherwise fights over. */
typedef struct Spawned {
    RayRec ray[2];
    uint mask;
} Spawned;

#if KDRT_MAX_DEPTH > 1
inline void spawn_ray(Spawned* sp, uint slot, real3 org, real3 dir, int from, uint pixel, real3 weight) {
    RayRec* r = &sp->ray[slot];
    r->org[0] = org.x; r->org[1] = org.y; r->org[2] = org.z;
    r->ignore = from;
    r->dir[0] = dir.x; r->dir[1] = dir.y; r->dir[2] = dir.z;
    r->pixel = pixel;
    r->weight[0] = weight.x; r->weight[1] = weight.y; r->weight[2] = weight.z;
#ifndef KDRT_DOUBLE
    r->zero = R(0); /* the fourth lane of weight (kernel_records.h, float triples) */
#endif
    sp->mask |= 1u << slot;
}
#endif

/* Writes a work-item's spawned rays to the queue from index `at` on. */
inline void append_spawned(__global RayRec* queue, uint capacity, uint at, const Spawned* sp) {
    if (sp->mask & 1u) {
        if (at < capacity) queue[at] = sp->ray[0]; /* the host sizes queues so that it always is */
        ++at;
    }
    if ((sp->mask & 2u) && at < capacity) queue[at] = sp->ray[1];
}

/* A ray of a bounce as shade_ray reads it: whole vectors. A camera ray made
 * just before is then read back as it was written; a RayRec written field by
 * field and read as vectors defeats a CPU's store forwarding. */
typedef struct BounceRay {
    real3 org, dir, weight;
    int ignore;
    uint pixel;
} BounceRay;

inline BounceRay queued_ray(__global const RayRec* r) {
    BounceRay b;
    b.org = load3(r->org);
    b.dir = load3(r->dir);
    b.weight = load3(r->weight);
    b.ignore = r->ignore;
    b.pixel = r->pixel;
    return b;
}

/* A hit being shaded: its surface, material and the colour so far. */
typedef struct Shading {
    Surface s;
    __global const GpuMaterial* m;
    real3 C; /* the material's colour */
    real3 c; /* the ray's colour so far, before its weight */
} Shading;

/* The first step of shading a ray given its closest hit: the camera rays'
 * ids, then either the surface and its ambient term in *sh, or for a miss
 * false (the ray brings the background). */
inline bool begin_shading(const Scene* scene, const BounceRay* in, const Ray* ray, Hit hit, __global int* ids,
                          __global float* hit_t, uint write_ids, Shading* sh) {
    if (write_ids) {
        ids[in->pixel] = hit.id;
        hit_t[in->pixel] = hit.id == KDRT_NONE_ID ? R(0) : (float)hit.t;
    }
    if (hit.id == KDRT_NONE_ID) return false;
    sh->s = make_surface(scene, ray, hit);
    sh->m = &scene->materials[sh->s.material];
    sh->C = load3(sh->m->color);
    sh->c = scene->ambient * sh->C * (real)sh->m->diffuse;
    return true;
}

#ifdef KDRT_HAS_LIGHTS
/* The shadow ray from a surface towards a light at lp, its length and the
 * unit direction L; false when the light is behind the surface. */
inline bool make_shadow_ray(const Surface* s, real3 lp, int from, Ray* shadow, real* t_max, real3* L_out) {
    real3 L = lp - s->p;
    const real dist = length3(L);
    L /= dist;
    if (!(dot3(s->ng, L) > R(0))) return false;
    const real3 org = offset_origin(s, L);
    *shadow = make_ray(org, L, LEAVING(from));
    *t_max = length3(lp - org);
    *L_out = L;
    return true;
}

/* What an unblocked light adds (diffuse and highlight) for a ray along view. */
inline real3 light_term(const Shading* sh, __global const LightRec* light, real3 L, real3 view) {
    const real3 R = R(2) * dot3(sh->s.ns, L) * sh->s.ns - L;
    const real spec = specular_power(fmax(R(0), dot3(R, -view)), (real)sh->m->shininess);
    return load3(light->color) *
           ((real)sh->m->diffuse * sh->C * fmax(R(0), dot3(sh->s.ns, L)) + (real)sh->m->specular * spec);
}
#endif

/* The last step: the mirror and refracted rays of the next bounce; returns
 * what the ray brings its pixel. */
inline real3 end_shading(const BounceRay* in, const Ray* ray, int hit_id, const Shading* sh, uint depth,
                         Spawned* spawned) {
    const real3 weight = in->weight, colour = weight * sh->c;
#if KDRT_MAX_DEPTH > 1
    if (depth >= KDRT_MAX_DEPTH) return colour;
    __global const GpuMaterial* m = sh->m;
#ifdef KDRT_HAS_REFLECTION
    if (m->reflect > R(0)) {
        const real3 R = ray->dir - R(2) * dot3(ray->dir, sh->s.ns) * sh->s.ns;
        spawn_ray(spawned, 0u, offset_origin(&sh->s, R), R, LEAVING(hit_id), in->pixel, weight * (real)m->reflect);
    }
#endif
#ifdef KDRT_HAS_REFRACTION
    if (m->transmit > R(0)) {
        const real eta = sh->s.inside ? (real)m->ior : R(1) / (real)m->ior;
        const real cos_i = -dot3(ray->dir, sh->s.ns);
        const real k = R(1) - eta * eta * (R(1) - cos_i * cos_i);
        const real3 T = k >= R(0) ? normalize3(eta * ray->dir + (eta * cos_i - sqrt(k)) * sh->s.ns)
                                  : ray->dir - R(2) * dot3(ray->dir, sh->s.ns) * sh->s.ns; /* total internal reflection */
        spawn_ray(spawned, 1u, offset_origin(&sh->s, T), T, LEAVING(hit_id), in->pixel, weight * (real)m->transmit);
    }
#endif
#endif
    return colour;
}

/* Traces and shades one ray of bounce `depth` (camera rays: depth 1);
 * returns its colour times its weight, what it adds to its pixel. */
inline real3 shade_ray(const Scene* scene, const BounceRay* in, uint depth, Spawned* spawned, __global int* ids,
                       __global float* hit_t, uint write_ids, uint* shadow_rays) {
    const Ray ray = make_ray(in->org, in->dir, in->ignore);
    const Hit hit = closest_hit(scene, &ray);
    Shading sh;
    if (!begin_shading(scene, in, &ray, hit, ids, hit_t, write_ids, &sh)) return in->weight * scene->background;
#ifdef KDRT_HAS_LIGHTS
    for (uint l = 0; l < scene->light_count; ++l) {
        __global const LightRec* light = &scene->lights[l];
        Ray shadow;
        real t_max;
        real3 L;
        if (!make_shadow_ray(&sh.s, load3(light->position), hit.id, &shadow, &t_max, &L)) continue;
        ++*shadow_rays;
        if (!occluded(scene, &shadow, t_max)) sh.c += light_term(&sh, light, L, ray.dir);
    }
#endif
    return end_shading(in, &ray, hit.id, &sh, depth, spawned);
}

#ifdef KDRT_PACKETS
/* Traces and shades rays in[0 .. n-1] of a bounce (n <= 4) together: their
 * closest hits, then each light's shadow rays, as packets where they can;
 * spawned[i] gets ray i's bounces, colour[i] its colour times its weight:
 * shade_ray's results. */
inline void shade_packet(const Scene* scene, const BounceRay* in, uint n, uint depth, Spawned* spawned,
                         real3* colour, __global int* ids, __global float* hit_t, uint write_ids,
                         uint* shadow_rays) {
    Ray rays[4];
    for (uint i = 0; i < n; ++i) rays[i] = make_ray(in[i].org, in[i].dir, in[i].ignore);
    const real unbounded[4] = {REAL_INF, REAL_INF, REAL_INF, REAL_INF};
    Hit hits[4];
    trace_lanes(scene, rays, (1u << n) - 1u, unbounded, false, hits);
    Shading sh[4];
    uint lit = 0u; /* the rays that hit something */
    for (uint i = 0; i < n; ++i) {
        if (begin_shading(scene, &in[i], &rays[i], hits[i], ids, hit_t, write_ids, &sh[i])) lit |= 1u << i;
        else colour[i] = in[i].weight * scene->background;
    }
#ifdef KDRT_HAS_LIGHTS
    for (uint l = 0; l < scene->light_count; ++l) {
        __global const LightRec* light = &scene->lights[l];
        const real3 lp = load3(light->position);
        Ray shadow[4];
        real t_max[4];
        real3 L[4];
        uint cast = 0u;
        for (uint k = lit; k != 0u; k &= k - 1u) {
            const uint i = lowest_lane(k);
            if (make_shadow_ray(&sh[i].s, lp, hits[i].id, &shadow[i], &t_max[i], &L[i])) cast |= 1u << i;
        }
        *shadow_rays += popcount(cast);
        Hit blockers[4];
        trace_lanes(scene, shadow, cast, t_max, true, blockers);
        for (uint k = cast; k != 0u; k &= k - 1u) {
            const uint i = lowest_lane(k);
            if (!blocks(blockers[i], t_max[i])) sh[i].c += light_term(&sh[i], light, L[i], rays[i].dir);
        }
    }
#endif
    for (uint k = lit; k != 0u; k &= k - 1u) {
        const uint i = lowest_lane(k);
        colour[i] = end_shading(&in[i], &rays[i], hits[i].id, &sh[i], depth, &spawned[i]);
    }
}
#endif
