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
 * Four lanes, not the eight of AVX: a kd-tree leaf holds a few triangles,
 * and eight lanes would mostly be empty. */

#ifdef KDRT_CPU_DEVICE
/* The rays of four lanes as the watertight test reads them: origins and
 * shear in the test's axis order. A packet's four rays (traverse_packet.cl),
 * or one ray in every lane for four triangles (test_triangles below). */
typedef struct PacketShear {
    real4 okx, oky, okz, sx, sy, sz;
    int kx, ky, kz;
    bool shared; /* every lane has the same kx, ky, kz: the vector test applies */
} PacketShear;

/* A leaf's triangles lie scattered over memory: asking for them all first
 * lets their cache misses overlap (prefetch_leaf in intersect_packet.h). */
inline void prefetch_leaf(const Scene* scene, __global const uint* ids, uint count) {
    for (uint i = 0; i < count && i < 16u; ++i)
        if (ids[i] >= scene->sphere_count) {
            __global const uchar* tri = (__global const uchar*)&scene->triangles[ids[i] - scene->sphere_count];
            KDRT_PREFETCH(tri);
            KDRT_PREFETCH(tri + sizeof(TriangleRec) - 1);
        }
}
#endif

#if defined(KDRT_CPU_DEVICE) && defined(KDRT_HAS_TRIANGLES) && !defined(KDRT_MOLLER_TRUMBORE)

/* intersect_triangle's steps for the lanes in `lanes` (p->shared), each line
 * intersect_triangle's, component by component; v0[a], v1[a], v2[a]: the
 * vertices' components on axis a, a triangle per lane or the same one in
 * every lane. Returns the lanes that hit, with t, b1 and b2 stored; *slow
 * gets the lanes whose answer needs the scalar test (a zero edge function in
 * float, redone in double where the device can; the plane-equation fallback;
 * a non-finite t). */
inline uint watertight_lanes(const PacketShear* p, uint lanes, const real4* v0, const real4* v1, const real4* v2,
                             real* t_out, real* b1_out, real* b2_out, uint* slow) {
    const real4 Akz = v0[p->kz] - p->okz, Bkz = v1[p->kz] - p->okz, Ckz = v2[p->kz] - p->okz;
    const real4 ax = (v0[p->kx] - p->okx) - p->sx * Akz, ay = (v0[p->ky] - p->oky) - p->sy * Akz;
    const real4 bx = (v1[p->kx] - p->okx) - p->sx * Bkz, by = (v1[p->ky] - p->oky) - p->sy * Bkz;
    const real4 cx = (v2[p->kx] - p->okx) - p->sx * Ckz, cy = (v2[p->ky] - p->oky) - p->sy * Ckz;
    const real4 u = cx * by - cy * bx;
    const real4 v = ax * cy - ay * cx;
    const real4 w = bx * ay - by * ax;
    const real4 zero = (real4)(R(0));
    *slow = 0u;
#ifndef KDRT_DOUBLE
    *slow = lane_bits((u == zero) | (v == zero) | (w == zero)) & lanes;
#endif
    const uint outside = lane_bits(((u < zero) | (v < zero) | (w < zero)) & ((u > zero) | (v > zero) | (w > zero)));
    const real4 det = u + v + w;
    uint live = lanes & ~*slow & ~outside & ~lane_bits(det == zero);
    if (live == 0u) return 0u;
    const real4 az = p->sz * Akz, bz = p->sz * Bkz, cz = p->sz * Ckz;
    const real4 T = u * az + v * bz + w * cz;
    const real4 t = T / det;
    /* The plane-equation fallback, and t not finite (t - t is NaN then): the scalar test. */
    const real4 zmax = fmax(fabs(az), fmax(fabs(bz), fabs(cz)));
    const uint rare = lane_bits((zmax > R(256) * fabs(t)) | ((t - t) != zero)) & live;
    *slow |= rare;
    live &= ~rare & lane_bits(t > zero);
    if (live != 0u) {
        vstore4(t, 0, t_out);
        vstore4(v / det, 0, b1_out);
        vstore4(w / det, 0, b2_out);
    }
    return live;
}

/* The ray in every lane, for a leaf's triangles four at a time. */
inline PacketShear ray_in_lanes(const Ray* ray) {
    PacketShear p;
    p.kx = ray->kx;
    p.ky = ray->ky;
    p.kz = ray->kz;
    p.shared = true;
    p.okx = (real4)(get3(ray->org, p.kx));
    p.oky = (real4)(get3(ray->org, p.ky));
    p.okz = (real4)(get3(ray->org, p.kz));
    p.sx = (real4)(ray->sx);
    p.sy = (real4)(ray->sy);
    p.sz = (real4)(ray->sz);
    return p;
}

/* watertight_lanes' answers, taken in lane order as the scalar loop takes
 * its objects: a hit lane is kept in *best if closer, a rare lane goes to
 * intersect_object, and with any_hit the first hit nearer than t_max ends
 * the batch (true). ids[i]: lane i's object. */
inline bool take_lanes(const Scene* scene, const Ray* ray, const uint* ids, uint live, uint slow, const real* ts,
                       const real* b1s, const real* b2s, bool any_hit, real t_max, Hit* best) {
    for (uint l = live | slow; l != 0u; l &= l - 1u) {
        const uint i = lowest_lane(l);
        const int id = (int)ids[i];
        if ((slow >> i) & 1u) {
            intersect_object(scene, ray, ids[i], best);
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

/* The triangles batch[0 .. n-1] (n <= 4) against the ray: one alone through
 * intersect_object (cheaper than a vector of one), more as lanes (unused
 * lanes repeat lane 0), taken in batch order (take_lanes), so an any-hit
 * ray stops at the same object as alone. */
inline bool test_triangles(const Scene* scene, const Ray* ray, const uint* batch, uint n, bool any_hit, real t_max,
                           Hit* best) {
    if (n == 0u) return false;
    if (n == 1u) {
        intersect_object(scene, ray, batch[0], best);
        return any_hit && best->t < t_max;
    }
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
    const PacketShear p = ray_in_lanes(ray);
    real ts[4], b1s[4], b2s[4];
    uint slow;
    const uint live = watertight_lanes(&p, (1u << n) - 1u, A, B, C, ts, b1s, b2s, &slow);
    return take_lanes(scene, ray, batch, live, slow, ts, b1s, b2s, any_hit, t_max, best);
}

/* A leaf's objects: closest hit, or with any_hit just whether one is nearer
 * than t_max. Returns the distance beyond which nothing matters any more.
 * Triangles are gathered four at a time. An any-hit ray takes the objects in
 * the leaf's order all the same (a sphere after the triangles gathered
 * before it), so it stops at the object the one-at-a-time loop stops at. */
inline real visit_objects(const Scene* scene, const Ray* ray, __global const uint* ids, uint count, bool any_hit,
                          real t_max, Mailbox* tested, Hit* best) {
    prefetch_leaf(scene, ids, count);
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
        if (test_triangles(scene, ray, batch, n, any_hit, t_max, best)) return -REAL_INF;
        n = 0u;
        if (id < scene->sphere_count) {
            intersect_object(scene, ray, id, best);
            if (any_hit && best->t < t_max) return -REAL_INF;
        }
    }
    if (test_triangles(scene, ray, batch, n, any_hit, t_max, best)) return -REAL_INF;
    return any_hit ? REAL_INF : best->t;
}

#ifdef KDRT_PACKED_LEAVES

/* A packed leaf's objects (GpuPackedLeaf, kernel_records.h), the twin of
 * test_packed_leaf in libkdrt/src/cpu/packed_leaves.h: its spheres one at a
 * time with the mailbox, then each block of four triangles as lanes, nine
 * vector loads where test_triangles gathers twelve vertices. A duplicated
 * triangle is not mailboxed: tested again it gives the same hit, which the
 * closest-hit rule (closer_than) and a shadow ray's yes or no ignore. Renders
 * and closest-hit and any-hit queries (Scene.packed): whichever hit stops an
 * any-hit query's walk, its answer is the same (stopped_past_end in
 * ray_query.cl). Returns what visit_objects returns. */
inline real visit_packed_leaf(const Scene* scene, const Ray* ray, GpuPackedLeaf leaf, bool any_hit, real t_max,
                              Mailbox* tested, Hit* best) {
    __global const uint* spheres = scene->leaf_spheres + leaf.first_sphere;
    for (uint k = 0; k < leaf.sphere_count; ++k) {
        if (mailbox_seen(tested, spheres[k])) continue;
        intersect_object(scene, ray, spheres[k], best);
        if (any_hit && best->t < t_max) return -REAL_INF;
    }
    if (leaf.block_count == 0u) return any_hit ? REAL_INF : best->t;
    const PacketShear p = ray_in_lanes(ray);
    __global const LeafBlockRec* block = scene->leaf_blocks + leaf.first_block;
    for (uint b = 0; b < leaf.block_count; ++b, ++block) {
        const int4 id4 = vload4(0, block->id);
        /* A flat triangle is never hit by a ray leaving it. */
        const uint lanes = block->lanes & ~int_lane_bits(id4 == (int4)(ray->ignore));
        if (lanes == 0u) continue;
        const real4 A[3] = {vload4(0, block->v[0][0]), vload4(0, block->v[0][1]), vload4(0, block->v[0][2])};
        const real4 B[3] = {vload4(0, block->v[1][0]), vload4(0, block->v[1][1]), vload4(0, block->v[1][2])};
        const real4 C[3] = {vload4(0, block->v[2][0]), vload4(0, block->v[2][1]), vload4(0, block->v[2][2])};
        real ts[4], b1s[4], b2s[4];
        uint slow;
        const uint live = watertight_lanes(&p, lanes, A, B, C, ts, b1s, b2s, &slow);
        if ((live | slow) == 0u) continue;
        uint ids[4];
        vstore4(as_uint4(id4), 0, ids);
        if (take_lanes(scene, ray, ids, live, slow, ts, b1s, b2s, any_hit, t_max, best)) return -REAL_INF;
    }
    return any_hit ? REAL_INF : best->t;
}
#endif

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
