/* traverse_packet.cl: four rays through the kd-tree together, the twin of
 * traverse_stack_packet (libkdrt/src/cpu/traverse_packet.h) and of
 * test_leaf_packet (intersect_packet.h). CPU devices only (KDRT_CPU_DEVICE),
 * over the stack traversal: there a work-item runs alone on a core, four
 * coherent rays share its node loads and branch decisions, and a triangle's
 * test runs on the four of them at once. A GPU already runs its work-items
 * side by side.
 *
 * Closest and any hits. Each lane gets exactly what traverse() gives its ray
 * alone: rays whose direction signs agree (packet_compatible) have the same
 * near child at every node, so each lane visits the same leaves in the same
 * order with the same [tmin, tmax] as alone, keeps its own mailbox, and
 * finishes at the same leaf; a triangle's vector test computes
 * intersect_triangle's values lane by lane, and a sphere's sphere_roots'.
 * Triangles when the lanes' shear axes differ, huge spheres, a ray leaving
 * a sphere and the tests' rare paths go through intersect_object lane by lane.
 *
 * trace_lanes, at the end, is the packets' entry for the render and query
 * kernels; with the BVH (KDRT_TRAVERSAL_BVH) its traverse_packet is the one
 * of traverse_bvh_packet.cl. */
#ifdef KDRT_PACKETS
#if KDRT_PACKETS != 4 || (KDRT_TRAVERSAL != 3 && KDRT_TRAVERSAL != KDRT_TRAVERSAL_BVH) || !defined(KDRT_CPU_DEVICE)
#error "KDRT_PACKETS: 4, with the kd-tree's stack traversal or the BVH on a CPU device"
#endif

/* Same nonzero direction sign on every axis, finite reciprocals: then one
 * near/far order holds for the whole packet. The twin's test, on the three
 * axes at once: get3's per-axis selects made it a seventh of PoCL's time on
 * 2x2x4's camera rays. */
inline bool packet_compatible(const Ray* rays) {
    const real3 zero = (real3)(R(0));
    const real3 d0 = rays[0].dir;
    bool compatible = true;
    for (int i = 0; i < 4; ++i) {
        const real3 d = rays[i].dir;
        compatible = compatible && all((d != zero) & ((d > zero) == (d0 > zero)) & isfinite(rays[i].inv_dir));
    }
    return compatible;
}

#if KDRT_TRAVERSAL == 3 /* the BVH's walk: traverse_bvh_packet.cl */
#define KDRT_LANES4(expr_i) ((real4)(expr_i(0), expr_i(1), expr_i(2), expr_i(3)))

inline PacketShear packet_shear(const Ray* rays) {
    PacketShear p;
    p.kx = rays[0].kx;
    p.ky = rays[0].ky;
    p.kz = rays[0].kz;
    p.shared = true;
    for (int i = 1; i < 4; ++i) p.shared = p.shared && rays[i].kx == p.kx && rays[i].ky == p.ky && rays[i].kz == p.kz;
#define KDRT_OKX(i) get3(rays[i].org, p.kx)
#define KDRT_OKY(i) get3(rays[i].org, p.ky)
#define KDRT_OKZ(i) get3(rays[i].org, p.kz)
#define KDRT_SX(i) rays[i].sx
#define KDRT_SY(i) rays[i].sy
#define KDRT_SZ(i) rays[i].sz
    p.okx = KDRT_LANES4(KDRT_OKX);
    p.oky = KDRT_LANES4(KDRT_OKY);
    p.okz = KDRT_LANES4(KDRT_OKZ);
    p.sx = KDRT_LANES4(KDRT_SX);
    p.sy = KDRT_LANES4(KDRT_SY);
    p.sz = KDRT_LANES4(KDRT_SZ);
#undef KDRT_OKX
#undef KDRT_OKY
#undef KDRT_OKZ
#undef KDRT_SX
#undef KDRT_SY
#undef KDRT_SZ
    return p;
}

#if defined(KDRT_HAS_SPHERES) && !defined(KDRT_TEXTBOOK_SPHERE)
/* sphere_roots for the lanes in `lanes` (org, dir: the rays' components by
 * axis) and a sphere of radius up to 2^60 (beyond, the scalar test's scaled
 * frame is needed), the twin of sphere_roots_packet (intersect_packet.h):
 * each line sphere_roots' expression, component by component in its order.
 * Returns the lanes whose ray meets the sphere, with both roots, t0 <= t1;
 * *slow gets the lanes with q = 0, which the scalar test answers. */
inline uint sphere_lanes(const real4* org, const real4* dir, uint lanes, real3 center, real radius, real* t0_out,
                         real* t1_out, uint* slow) {
    const real4 fx = org[0] - center.x, fy = org[1] - center.y, fz = org[2] - center.z;
    const real4 b = -((fx * dir[0] + fy * dir[1]) + fz * dir[2]);
    const real4 lx = fx + b * dir[0], ly = fy + b * dir[1], lz = fz + b * dir[2];
    const real r2 = radius * radius;
    const real4 disc = r2 - ((lx * lx + ly * ly) + lz * lz);
    const real4 zero = (real4)(R(0));
    uint live = lanes & ~lane_bits(disc < zero);
    *slow = 0u;
    if (live == 0u) return 0u;
    const real4 c = ((fx * fx + fy * fy) + fz * fz) - r2;
    const real4 q = b + copysign(sqrt(fmax(disc, zero)), b);
    *slow = lane_bits(q == zero) & live;
    live &= ~*slow;
    vstore4(fmin(c / q, q), 0, t0_out);
    vstore4(fmax(c / q, q), 0, t1_out);
    return live;
}
#endif

/* A leaf's objects for the lanes in `lanes`, each with its own mailbox and
 * best hit (org, dir: the rays' components by axis, for spheres). With
 * any_hit a lane stops at a hit nearer than its t_max, as visit_objects
 * stops; returns the lanes that did (0 for closest hits). */
inline uint visit_packet(const Scene* scene, const Ray* rays, const PacketShear* p, const real4* org, const real4* dir,
                         uint lanes, __global const uint* ids, uint count, bool any_hit, const real* t_max,
                         Mailbox* tested, Hit* best) {
    uint blocked = 0u;
    prefetch_leaf(scene, ids, count);
    for (uint k = 0; k < count && lanes != 0u; ++k) {
        const uint id = ids[k];
        uint todo = 0u;
        for (uint l = lanes; l != 0u; l &= l - 1u) {
            const uint i = lowest_lane(l);
            if (!mailbox_seen(&tested[i], id)) todo |= 1u << i;
        }
        if (todo == 0u) continue;
        uint slow = todo;
#if defined(KDRT_HAS_SPHERES) && !defined(KDRT_TEXTBOOK_SPHERE)
        if (id < scene->sphere_count) {
            __global const SphereRec* sphere = &scene->spheres[id];
            if (sphere->radius <= R(1.152921504606846976e18)) { /* 2^60, as sphere_roots */
                uint leaving = 0u; /* intersect_sphere's own rule for a ray leaving this sphere */
                for (uint l = todo; l != 0u; l &= l - 1u)
                    if (rays[lowest_lane(l)].ignore == (int)id) leaving |= l & (0u - l);
                real t0[4], t1[4];
                const uint hits =
                    sphere_lanes(org, dir, todo & ~leaving, load3(sphere->center), sphere->radius, t0, t1, &slow);
                slow |= leaving;
                for (uint l = hits; l != 0u; l &= l - 1u) {
                    const uint i = lowest_lane(l);
                    const real t = t0[i] > R(0) ? t0[i] : t1[i]; /* intersect_sphere's root */
                    if (t > R(0) && closer_than(t, (int)id, best[i])) {
                        best[i].t = t;
                        best[i].id = (int)id;
                        best[i].b1 = R(0);
                        best[i].b2 = R(0);
                    }
                }
            }
        }
#endif
#if defined(KDRT_HAS_TRIANGLES) && !defined(KDRT_MOLLER_TRUMBORE)
        if (id >= scene->sphere_count && p->shared) {
            for (uint l = todo; l != 0u; l &= l - 1u) /* a flat triangle is never hit by a ray leaving it */
                if (rays[lowest_lane(l)].ignore == (int)id) todo &= ~(l & (0u - l));
            slow = 0u;
            if (todo == 0u) continue;
            /* The same triangle in every lane. */
            __global const TriangleRec* tri = &scene->triangles[id - scene->sphere_count];
            const real3 a = vload3(0, tri->v0), b = vload3(0, tri->v1), c = vload3(0, tri->v2);
            const real4 A[3] = {(real4)(a.x), (real4)(a.y), (real4)(a.z)};
            const real4 B[3] = {(real4)(b.x), (real4)(b.y), (real4)(b.z)};
            const real4 C[3] = {(real4)(c.x), (real4)(c.y), (real4)(c.z)};
            real t[4], b1[4], b2[4];
            const uint hits = watertight_lanes(p, todo, A, B, C, t, b1, b2, &slow);
            for (uint l = hits; l != 0u; l &= l - 1u) {
                const uint i = lowest_lane(l);
                if (closer_than(t[i], (int)id, best[i])) {
                    best[i].t = t[i];
                    best[i].id = (int)id;
                    best[i].b1 = b1[i];
                    best[i].b2 = b2[i];
                }
            }
        }
#endif
        for (uint l = slow; l != 0u; l &= l - 1u) {
            const uint i = lowest_lane(l);
            intersect_object(scene, &rays[i], id, &best[i]);
        }
        if (any_hit)
            for (uint l = lanes; l != 0u; l &= l - 1u) {
                const uint i = lowest_lane(l);
                if (best[i].t < t_max[i]) blocked |= 1u << i;
            }
        lanes &= ~blocked;
    }
    return blocked;
}

/* traverse() for the lanes in `valid` of packet_compatible rays, lane by
 * lane: closest hits into best[i], or with any_hit a hit nearer than
 * t_max[i] (a lane then stops, its best nearer than t_max). */
inline void traverse_packet(const Scene* scene, const Ray* rays, uint valid, const real* t_max, bool any_hit,
                            Hit* best) {
    real t0s[4], t1s[4];
    uint active = 0u;
    for (int i = 0; i < 4; ++i) {
        best[i] = no_hit();
        t0s[i] = t1s[i] = R(0);
        if (((valid >> i) & 1u) && clip_to_box(scene, &rays[i], t_max[i], &t0s[i], &t1s[i])) active |= 1u << i;
    }
    uint live = active; /* lanes that have not finished */
    if (live == 0u) return;
    const PacketShear shear = packet_shear(rays);
#define KDRT_ORG(a, i) get3(rays[i].org, a)
#define KDRT_DIR(a, i) get3(rays[i].dir, a)
#define KDRT_INV(a, i) get3(rays[i].inv_dir, a)
#define KDRT_AXIS4(F, a) ((real4)(F(a, 0), F(a, 1), F(a, 2), F(a, 3)))
    const real4 org[3] = {KDRT_AXIS4(KDRT_ORG, 0), KDRT_AXIS4(KDRT_ORG, 1), KDRT_AXIS4(KDRT_ORG, 2)};
    const real4 dir[3] = {KDRT_AXIS4(KDRT_DIR, 0), KDRT_AXIS4(KDRT_DIR, 1), KDRT_AXIS4(KDRT_DIR, 2)};
    const real4 inv[3] = {KDRT_AXIS4(KDRT_INV, 0), KDRT_AXIS4(KDRT_INV, 1), KDRT_AXIS4(KDRT_INV, 2)};
#undef KDRT_ORG
#undef KDRT_DIR
#undef KDRT_INV
#undef KDRT_AXIS4
    /* Bit a: the packet's direction is positive on axis a (the same for every lane). */
    uint positive = 0u;
    for (int a = 0; a < 3; ++a) positive |= (get3(rays[0].dir, a) > R(0) ? 1u : 0u) << a;
    Mailbox tested[4];
    for (int i = 0; i < 4; ++i) clear_mailbox(&tested[i]);
    real4 stack_tmin[KDRT_MAX_TREE_DEPTH + 2], stack_tmax[KDRT_MAX_TREE_DEPTH + 2];
    uint stack_node[KDRT_MAX_TREE_DEPTH + 2], stack_active[KDRT_MAX_TREE_DEPTH + 2];
    int top = 0;
    uint node = 0u;
    real4 tmin = vload4(0, t0s), tmax = vload4(0, t1s);
    for (;;) {
        const KdNode n = scene->nodes[node];
        if (active != 0u && !kd_is_leaf(n)) {
            const int axis = kd_axis(n);
            const real split = kd_split(n);
            const uint below = node + 1u, above = kd_above_child(n);
            KDRT_PREFETCH(&scene->nodes[above]);
            const bool below_first = ((positive >> axis) & 1u) != 0u;
            const uint near_child = below_first ? below : above, far_child = below_first ? above : below;
            /* Per lane as in traverse(): t_split <= tmin: far only; t_split >= tmax: near only; else both. */
            const real4 ts = (split - org[axis]) * inv[axis];
            const uint wants_near = lane_bits(ts > tmin) & active;
            const uint wants_far = lane_bits((ts <= tmin) | (ts < tmax)) & active;
            if (wants_near == 0u) {
                node = far_child;
            } else if (wants_far == 0u) {
                node = near_child;
            } else {
                stack_node[top] = far_child;
                stack_active[top] = wants_far;
                stack_tmin[top] = select(tmin, ts, ts > tmin);
                stack_tmax[top] = tmax;
                ++top;
                tmax = select(tmax, ts, ts < tmax);
                node = near_child;
                active = wants_near;
            }
            continue;
        }
        if (active != 0u) {
            const uint blocked = visit_packet(scene, rays, &shear, org, dir, active, scene->leaf_objects + n.word0,
                                              n.word1 >> 2, any_hit, t_max, tested, best);
            if (any_hit) {
                live &= ~blocked; /* the others go on: their visit says +inf */
            } else {
                real exits[4];
                vstore4(tmax, 0, exits);
                for (uint l = active; l != 0u; l &= l - 1u) {
                    const uint i = lowest_lane(l);
                    if (leaf_finishes(&rays[i], best[i].t, exits[i])) live &= ~(1u << i);
                }
            }
        }
        if (live == 0u || top == 0) return;
        --top;
        node = stack_node[top];
        active = stack_active[top] & live;
        tmin = stack_tmin[top];
        tmax = stack_tmax[top];
    }
}

#endif /* KDRT_TRAVERSAL == 3 */

/* Rays rays[i] for the lanes of `lanes` (the others: any finite ray),
 * closest hits or with any_hit whether one is nearer than t_max[i]: as a
 * packet when two or more lanes are compatible, else one by one. */
inline void trace_lanes(const Scene* scene, Ray* rays, uint lanes, const real* t_max, bool any_hit, Hit* hits) {
    if (popcount(lanes) >= 2) {
        const Ray first = rays[lowest_lane(lanes)];
        for (uint i = 0; i < 4u; ++i)
            if (!((lanes >> i) & 1u)) rays[i] = first; /* unused lanes borrow a used one's ray */
        if (packet_compatible(rays)) {
            traverse_packet(scene, rays, lanes, t_max, any_hit, hits);
            return;
        }
    }
    for (uint l = lanes; l != 0u; l &= l - 1u) {
        const uint i = lowest_lane(l);
        hits[i] = no_hit();
        traverse(scene, &rays[i], t_max[i], any_hit, &hits[i]);
    }
}
#endif
