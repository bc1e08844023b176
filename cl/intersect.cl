/* intersect.cl: ray/object tests, the twin of libkdrt/src/cpu/intersect.h. */

/* Watertight ray/triangle test (Woop, Benthin, Wald, JCGT 2013); zero edge
 * functions are recomputed in double where the device has it. */
inline bool intersect_triangle(const Ray* ray, real3 v0, real3 v1, real3 v2, real* t_out, real* b1_out, real* b2_out) {
    const real3 A = v0 - ray->org, B = v1 - ray->org, C = v2 - ray->org;
    const real ax = get3(A, ray->kx) - ray->sx * get3(A, ray->kz), ay = get3(A, ray->ky) - ray->sy * get3(A, ray->kz);
    const real bx = get3(B, ray->kx) - ray->sx * get3(B, ray->kz), by = get3(B, ray->ky) - ray->sy * get3(B, ray->kz);
    const real cx = get3(C, ray->kx) - ray->sx * get3(C, ray->kz), cy = get3(C, ray->ky) - ray->sy * get3(C, ray->kz);
    real u = cx * by - cy * bx;
    real v = ax * cy - ay * cx;
    real w = bx * ay - by * ax;
#ifdef KDRT_HAS_FP64
    if (u == 0.0f || v == 0.0f || w == 0.0f) {
        u = (real)((double)cx * (double)by - (double)cy * (double)bx);
        v = (real)((double)ax * (double)cy - (double)ay * (double)cx);
        w = (real)((double)bx * (double)ay - (double)by * (double)ax);
    }
#endif
    if ((u < 0.0f || v < 0.0f || w < 0.0f) && (u > 0.0f || v > 0.0f || w > 0.0f)) return false;
    const real det = u + v + w;
    if (det == 0.0f) return false;
    const real az = ray->sz * get3(A, ray->kz), bz = ray->sz * get3(B, ray->kz), cz = ray->sz * get3(C, ray->kz);
    const real T = u * az + v * bz + w * cz;
    const real t = T / det;
    if (!(t > 0.0f)) return false;
    *t_out = t;
    *b1_out = v / det;
    *b2_out = w / det;
    return true;
}

/* Ray/sphere after Haines et al. (Ray Tracing Gems ch. 7); a ray leaving this
 * sphere only hits its far side, and only heading inwards. */
inline bool intersect_sphere(const Ray* ray, int id, real3 center, real radius, real* t_out) {
    const real3 f = ray->org - center;
    const real b = -dot(f, ray->dir);
    const real3 l = f + b * ray->dir;
    const real r2 = radius * radius;
    const real disc = r2 - dot(l, l);
    if (disc < 0.0f) return false;
    const real c = dot(f, f) - r2;
    const real q = b + copysign(sqrt(disc), b);
    real t0, t1;
    if (q == 0.0f) {
        if (c > 0.0f) return false;
        t0 = t1 = 0.0f;
    } else {
        t0 = c / q;
        t1 = q;
        if (t0 > t1) {
            real tmp = t0;
            t0 = t1;
            t1 = tmp;
        }
    }
    if (id == ray->ignore) {
        if (dot(ray->dir, ray->org - center) >= 0.0f) return false;
        if (!(t1 > 0.0f)) return false;
        *t_out = t1;
        return true;
    }
    if (t0 > 0.0f) { *t_out = t0; return true; }
    if (t1 > 0.0f) { *t_out = t1; return true; }
    return false;
}

/* Tests object `id`, keeping it in *best when closer. */
inline void intersect_object(const Scene* scene, const Ray* ray, uint id, Hit* best) {
    real t, b1 = 0.0f, b2 = 0.0f;
    const int sid = (int)id;
#ifdef KDRT_HAS_SPHERES
    if (id < scene->sphere_count) {
        __global const GpuSphere* s = &scene->spheres[id];
        if (!intersect_sphere(ray, sid, load3(s->center), s->radius, &t)) return;
    } else
#endif
    {
#ifdef KDRT_HAS_TRIANGLES
        if (sid == ray->ignore) return;
        __global const GpuTriangle* tri = &scene->triangles[id - scene->sphere_count];
        if (!intersect_triangle(ray, load3(tri->v0), load3(tri->v1), load3(tri->v2), &t, &b1, &b2)) return;
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

/* A leaf's objects: closest hit, or with any_hit just whether one is nearer
 * than t_max. Returns the distance beyond which nothing matters any more. */
inline real visit_objects(const Scene* scene, const Ray* ray, __global const uint* ids, uint count, bool any_hit,
                          real t_max, Hit* best) {
    for (uint i = 0; i < count; ++i) {
        intersect_object(scene, ray, ids[i], best);
        if (any_hit && best->t < t_max) return -REAL_INF;
    }
    return any_hit ? REAL_INF : best->t;
}
