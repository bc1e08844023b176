/* visit_objects.cl: a leaf's objects for one ray, the twin of the C++ leaf
 * tests (test_leaf_ray in libkdrt/src/cpu/intersect_packet.h, and the plain
 * loops of ray_query_tracer.h and scene_tracer.h).
 *
 * On a CPU device (KDRT_CPU_DEVICE) a leaf's triangles are taken four at a
 * time, one per lane of a float4 (double4), through the watertight test's
 * steps as vector operations: PoCL makes SSE or AVX instructions of them,
 * where it cannot vectorise across work-items. Each lane computes exactly
 * what intersect_triangle computes; its rare paths (a zero edge function in
 * float, the plane-equation fallback, a non-finite t) are left to
 * intersect_object. A GPU gets no lanes: its SIMD already runs across
 * work-items, and a vector per work-item would only cost registers.
 * Four lanes, not the eight of AVX: the study's leaves hold about three
 * triangles (purple-wall), and eight lanes were slower there and no faster
 * on the big meshes. */

#if defined(KDRT_CPU_DEVICE) && defined(KDRT_HAS_TRIANGLES) && !defined(KDRT_MOLLER_TRUMBORE)

/* The triangles batch[0 .. n-1] (2 <= n <= 4; unused lanes repeat lane 0)
 * against the ray. The lanes are taken in batch order, as the scalar loop
 * takes them: a hit lane is kept in *best if closer, a rare lane goes to
 * intersect_object, and with any_hit the first hit nearer than t_max ends
 * the batch (true), so an any-hit ray stops at the same object as alone. */
inline bool test_triangle_lanes(const Scene* scene, const Ray* ray, const uint* batch, uint n, bool any_hit,
                                real t_max, Hit* best) {
    /* Whole vertices, put into lanes by component: loads of one component
     * per lane became slow gather instructions, and lanes stored one by one
     * into memory stalled the vector load that followed. */
#define KDRT_VERTICES(i)                                                                                      \
    __global const TriangleRec* tri##i = &scene->triangles[batch[(i) < n ? (i) : 0] - scene->sphere_count]; \
    const real3 a##i = vload3(0, tri##i->v0), b##i = vload3(0, tri##i->v1), c##i = vload3(0, tri##i->v2);
    KDRT_VERTICES(0) KDRT_VERTICES(1) KDRT_VERTICES(2) KDRT_VERTICES(3)
#undef KDRT_VERTICES
#define KDRT_LANES(v, c) ((real4)((v##0).c, (v##1).c, (v##2).c, (v##3).c))
    const real4 A[3] = {KDRT_LANES(a, x), KDRT_LANES(a, y), KDRT_LANES(a, z)};
    const real4 B[3] = {KDRT_LANES(b, x), KDRT_LANES(b, y), KDRT_LANES(b, z)};
    const real4 C[3] = {KDRT_LANES(c, x), KDRT_LANES(c, y), KDRT_LANES(c, z)};
#undef KDRT_LANES
    const int kx = ray->kx, ky = ray->ky, kz = ray->kz;
    const real ox = get3(ray->org, kx), oy = get3(ray->org, ky), oz = get3(ray->org, kz);
    /* Each line is intersect_triangle's, component by component. */
    const real4 Akz = A[kz] - oz, Bkz = B[kz] - oz, Ckz = C[kz] - oz;
    const real4 ax = (A[kx] - ox) - ray->sx * Akz, ay = (A[ky] - oy) - ray->sy * Akz;
    const real4 bx = (B[kx] - ox) - ray->sx * Bkz, by = (B[ky] - oy) - ray->sy * Bkz;
    const real4 cx = (C[kx] - ox) - ray->sx * Ckz, cy = (C[ky] - oy) - ray->sy * Ckz;
    const real4 u = cx * by - cy * bx;
    const real4 v = ax * cy - ay * cx;
    const real4 w = bx * ay - by * ax;
    const real4 zero = (real4)(R(0));
    const uint used = (1u << n) - 1u;
    uint slow = 0u;
#ifndef KDRT_DOUBLE
    slow = lane_bits((u == zero) | (v == zero) | (w == zero)) & used; /* redone in double where the device can */
#endif
    const uint outside = lane_bits(((u < zero) | (v < zero) | (w < zero)) & ((u > zero) | (v > zero) | (w > zero)));
    const real4 det = u + v + w;
    uint live = used & ~slow & ~outside & ~lane_bits(det == zero);
    real ts[4], b1s[4], b2s[4];
    if (live != 0u) {
        const real4 az = ray->sz * Akz, bz = ray->sz * Bkz, cz = ray->sz * Ckz;
        const real4 T = u * az + v * bz + w * cz;
        const real4 t = T / det;
        /* The plane-equation fallback, and t not finite (t - t is NaN then): the scalar test. */
        const real4 zmax = fmax(fabs(az), fmax(fabs(bz), fabs(cz)));
        const uint rare = lane_bits((zmax > R(256) * fabs(t)) | ((t - t) != zero)) & live;
        slow |= rare;
        live &= ~rare & lane_bits(t > zero);
        if (live != 0u) {
            vstore4(t, 0, ts);
            vstore4(v / det, 0, b1s);
            vstore4(w / det, 0, b2s);
        }
    }
    for (uint l = live | slow; l != 0u; l &= l - 1u) {
        const uint i = 31u - clz(l & (0u - l));
        const int id = (int)batch[i];
        if ((slow >> i) & 1u) {
            intersect_object(scene, ray, batch[i], best);
        } else if (closer_than(ts[i], id, *best)) {
            best->t = ts[i];
            best->id = id;
            best->b1 = b1s[i];
            best->b2 = b2s[i];
        }
        if (any_hit && best->t < t_max) return true;
    }
    return false;
}

/* A leaf's objects: closest hit, or with any_hit just whether one is nearer
 * than t_max. Returns the distance beyond which nothing matters any more.
 * Triangles are gathered four at a time. An any-hit ray takes the objects in
 * the leaf's order all the same (a sphere after the triangles gathered
 * before it), so it stops at the object the one-at-a-time loop stops at: a
 * ray query then checks the same hit against its window on every device. */
inline real visit_objects(const Scene* scene, const Ray* ray, __global const uint* ids, uint count, bool any_hit,
                          real t_max, Mailbox* tested, Hit* best) {
    /* The leaf's triangles lie scattered over memory: asking for them all
     * first lets their cache misses overlap (prefetch_leaf in intersect_packet.h). */
    for (uint i = 0; i < count && i < 16u; ++i)
        if (ids[i] >= scene->sphere_count) {
            __global const uchar* tri = (__global const uchar*)&scene->triangles[ids[i] - scene->sphere_count];
            KDRT_PREFETCH(tri);
            KDRT_PREFETCH(tri + sizeof(TriangleRec) - 1);
        }
    uint batch[4];
    uint n = 0u;
    for (uint i = 0; i < count; ++i) {
        const uint id = ids[i];
        if (mailbox_seen(tested, id)) continue;
        if ((int)id == ray->ignore && id >= scene->sphere_count) continue; /* a flat triangle is never hit by a ray leaving it */
        if (id >= scene->sphere_count) {
            batch[n++] = id;
            if (n < 4u) continue;
        } else if (!any_hit) { /* closest hits do not depend on the order */
            intersect_object(scene, ray, id, best);
            continue;
        }
        /* A full batch, or a sphere after the triangles gathered before it. */
        if (n == 1u) {  /* a lone triangle: the scalar test is cheaper than a vector of one */
            intersect_object(scene, ray, batch[0], best);
            if (any_hit && best->t < t_max) return -REAL_INF;
        } else if (n > 1u && test_triangle_lanes(scene, ray, batch, n, any_hit, t_max, best)) {
            return -REAL_INF;
        }
        n = 0u;
        if (id < scene->sphere_count) {
            intersect_object(scene, ray, id, best);
            if (any_hit && best->t < t_max) return -REAL_INF;
        }
    }
    if (n == 1u) {
        intersect_object(scene, ray, batch[0], best);
    } else if (n > 1u && test_triangle_lanes(scene, ray, batch, n, any_hit, t_max, best)) {
        return -REAL_INF;
    }
    if (any_hit && best->t < t_max) return -REAL_INF;
    return any_hit ? REAL_INF : best->t;
}

#else /* one object at a time */

inline real visit_objects(const Scene* scene, const Ray* ray, __global const uint* ids, uint count, bool any_hit,
                          real t_max, Mailbox* tested, Hit* best) {
    for (uint i = 0; i < count; ++i) {
        if (mailbox_seen(tested, ids[i])) continue;
        intersect_object(scene, ray, ids[i], best);
        if (any_hit && best->t < t_max) return -REAL_INF;
    }
    return any_hit ? REAL_INF : best->t;
}

#endif
