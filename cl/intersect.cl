/* intersect.cl: ray/object tests, the twin of libkdrt/src/cpu/intersect.h. */

/* Watertight ray/triangle test (Woop, Benthin, Wald, JCGT 2013); zero edge
 * functions are recomputed in double where the device has it. */
inline bool intersect_triangle(const Ray* ray, real3 v0, real3 v1, real3 v2, real* t_out, real* b1_out, real* b2_out) {
    const real3 A = v0 - ray->org, B = v1 - ray->org, C = v2 - ray->org;
    const real Akz = get3(A, ray->kz), Bkz = get3(B, ray->kz), Ckz = get3(C, ray->kz);
    const real ax = get3(A, ray->kx) - ray->sx * Akz, ay = get3(A, ray->ky) - ray->sy * Akz;
    const real bx = get3(B, ray->kx) - ray->sx * Bkz, by = get3(B, ray->ky) - ray->sy * Bkz;
    const real cx = get3(C, ray->kx) - ray->sx * Ckz, cy = get3(C, ray->ky) - ray->sy * Ckz;
    real u = cx * by - cy * bx;
    real v = ax * cy - ay * cx;
    real w = bx * ay - by * ax;
#if defined(KDRT_HAS_FP64) && !defined(KDRT_DOUBLE)
    if (u == R(0) || v == R(0) || w == R(0)) {
        u = (real)((double)cx * (double)by - (double)cy * (double)bx);
        v = (real)((double)ax * (double)cy - (double)ay * (double)cx);
        w = (real)((double)bx * (double)ay - (double)by * (double)ax);
    }
#endif
    if ((u < R(0) || v < R(0) || w < R(0)) && (u > R(0) || v > R(0) || w > R(0))) return false;
    const real det = u + v + w;
    if (det == R(0)) return false;
    const real az = ray->sz * Akz, bz = ray->sz * Bkz, cz = ray->sz * Ckz;
    const real T = u * az + v * bz + w * cz;
    real t = T / det;
    /* Far vertices cancel in T (a huge triangle seen close up): the plane
     * equation, as in intersect.h. */
    const real zmax = fmax(fabs(az), fmax(fabs(bz), fabs(cz)));
    if (zmax > R(256) * fabs(t) || !isfinite(t)) {
        const real3 n = cross3(v1 - v0, v2 - v0);
        t = dot3(n, A) / dot3(n, ray->dir);
    }
    if (!(t > R(0)) || !isfinite(t)) return false;
    *t_out = t;
    *b1_out = v / det;
    *b2_out = w / det;
    return true;
}

#ifdef KDRT_MOLLER_TRUMBORE
/* Moller-Trumbore (1997), the accuracy knob's cheaper and leakier choice. */
inline bool intersect_triangle_moller(const Ray* ray, real3 v0, real3 v1, real3 v2, real* t_out, real* b1_out,
                                      real* b2_out) {
    const real3 e1 = v1 - v0, e2 = v2 - v0;
    const real3 p = cross3(ray->dir, e2);
    const real det = dot3(e1, p);
    if (det == R(0)) return false;
    const real inv = R(1) / det;
    const real3 s = ray->org - v0;
    const real u = dot3(s, p) * inv;
    if (u < R(0) || u > R(1)) return false;
    const real3 q = cross3(s, e1);
    const real v = dot3(ray->dir, q) * inv;
    if (v < R(0) || u + v > R(1)) return false;
    const real t = dot3(e2, q) * inv;
    if (!(t > R(0))) return false;
    *t_out = t;
    *b1_out = u;
    *b2_out = v;
    return true;
}
#endif

/* Both roots of the ray/sphere quadratic in ascending order, the twin of
 * sphere_roots in libkdrt/src/cpu/intersect.h: after Haines et al. (Ray
 * Tracing Gems ch. 7), or the textbook formula with KDRT_TEXTBOOK_SPHERE
 * (accuracy knob: b^2 - c cancels for small or far spheres). */
inline bool sphere_roots(const Ray* ray, real3 center, real radius, real* t0, real* t1) {
    const real3 f = ray->org - center;
#ifdef KDRT_TEXTBOOK_SPHERE
    const real b = dot3(f, ray->dir);
    const real disc = b * b - (dot3(f, f) - radius * radius);
    if (disc < R(0)) return false;
    *t0 = -b - sqrt(disc);
    *t1 = -b + sqrt(disc);
    return true;
#else
    /* A radius whose square overflows is worked in units of 2^64 (exact). */
    real3 fs = f;
    real scale = R(1);
    if (radius > R(1.152921504606846976e18)) {
        fs *= R(5.42101086242752217e-20);
        radius *= R(5.42101086242752217e-20);
        scale = R(18446744073709551616.0);
    }
    const real b = -dot3(fs, ray->dir);
    const real3 l = fs + b * ray->dir;
    const real r2 = radius * radius;
    const real disc = r2 - dot3(l, l);
    if (disc < R(0)) return false;
    const real c = dot3(fs, fs) - r2;
    const real q = b + copysign(sqrt(disc), b);
    if (q == R(0)) {
        *t0 = *t1 = R(0);
        return c <= R(0);
    }
    *t0 = scale * fmin(c / q, q);
    *t1 = scale * fmax(c / q, q);
    return true;
#endif
}

/* A ray leaving this sphere only hits its far side, and only heading inwards. */
inline bool intersect_sphere(const Ray* ray, int id, real3 center, real radius, real* t_out) {
    real t0, t1;
    if (!sphere_roots(ray, center, radius, &t0, &t1)) return false;
    if (id == ray->ignore) {
        if (dot3(ray->dir, ray->org - center) >= R(0)) return false;
        if (!(t1 > R(0))) return false;
        *t_out = t1;
        return true;
    }
    if (t0 > R(0)) { *t_out = t0; return true; }
    if (t1 > R(0)) { *t_out = t1; return true; }
    return false;
}

#ifdef KDRT_HAS_TRIANGLES
/* Triangle `id` (an object id) with the test the program is built for. */
inline bool hit_triangle(const Scene* scene, const Ray* ray, uint id, real* t, real* b1, real* b2) {
    __global const TriangleRec* tri = &scene->triangles[id - scene->sphere_count];
#ifdef KDRT_MOLLER_TRUMBORE
    return intersect_triangle_moller(ray, load3(tri->v0), load3(tri->v1), load3(tri->v2), t, b1, b2);
#else
    return intersect_triangle(ray, load3(tri->v0), load3(tri->v1), load3(tri->v2), t, b1, b2);
#endif
}
#endif

/* Tests object `id`, keeping it in *best when closer. */
inline void intersect_object(const Scene* scene, const Ray* ray, uint id, Hit* best) {
    real t, b1 = R(0), b2 = R(0);
    const int sid = (int)id;
#ifdef KDRT_HAS_SPHERES
    if (id < scene->sphere_count) {
        __global const SphereRec* s = &scene->spheres[id];
        if (!intersect_sphere(ray, sid, load3(s->center), s->radius, &t)) return;
    } else
#endif
    {
#ifdef KDRT_HAS_TRIANGLES
        if (sid == ray->ignore) return;
        if (!hit_triangle(scene, ray, id, &t, &b1, &b2)) return;
#else
        return;
#endif
    }
    if (closer_than(t, sid, *best)) {
        best->t = t;
        best->id = sid;
        best->b1 = b1;
        best->b2 = b2;
    }
}
