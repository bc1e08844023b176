/* traverse_bvh.cl: the wide BVH (GpuBvhNode, kernel_records.h) walked nearest
 * first with a stack (an any-hit walk on CPU devices: in slot order), the twin
 * of traverse_bvh in libkdrt/src/cpu/traverse_bvh.h, whose comment explains
 * the box test: slab distances (plane - origin) * (1 / direction), the far
 * planes' reciprocal times 1 + 8u, the planes chosen by the reciprocal's sign,
 * a NaN distance (a ray lying in a slab's plane) that only widens the
 * interval; and the termination slack. Boxes are floats; a double ray tests
 * them in double. Leaves go through visit_range (traverse_common.cl), so an
 * any-hit query stops at its first hit; renders, closest and any-hit queries
 * on a CPU device walk the packed copy of the nodes, whose leaf slots refer to
 * their triangle blocks (visit_bvh_leaf), as the twin does. No mailbox: a BVH
 * refers to every object once.
 *
 * CPU devices (KDRT_CPU_DEVICE) test a node's eight boxes a plane at a time
 * as one float8 (double8), which PoCL makes SSE or AVX instructions of, and
 * keep the twin's stack: each hit child with its entry distance, sorted so
 * that the nearest is on top, or for any-hit walks in the node's slot order
 * as the twin's ChildOrder::AsStored (KDRT_BVH_SORTED_STACK_SIZE entries: 5388
 * bytes in float, 7184 in double, on the thread's stack under PoCL). Their
 * work-items take four rays and walk coherent ones together
 * (traverse_bvh_packet.cl, with a larger stack); this walk takes the rest.
 *
 * GPUs test the slots one after another (their SIMD runs across work-items)
 * and keep one 8-byte entry per node on the path, the node and its hit
 * slots still to visit, nearest first (KDRT_BVH_SLOT_STACK_SIZE entries: 512
 * bytes in either precision): the node groups of Ylitie, Karras and Laine
 * ("Efficient Incoherent Ray Traversal on GPUs Through Compressed Wide
 * BVHs", HPG 2017), here with the slots in the twin's exact order (by
 * entry distance) instead of the ray octant's, over uncompressed nodes read
 * slot by slot (GpuBvhSlot, bvh_node.cl: two 16-byte loads a slot). A GPU
 * keeps a private array it indexes at run time in off-chip memory (NVIDIA's
 * local memory, cached in L1), allocated for every thread the device can
 * hold: the sorted stack would be 5-7 KB a thread there. Popping a slot
 * recomputes its entry distance (its three near planes) instead of storing
 * it: the same operations on the same values, so the same distance, and the
 * same leaves in the same order. */
#if KDRT_TRAVERSAL == KDRT_TRAVERSAL_BVH

/* The far planes' conservative factor, 1 + 8u (kBoxFarScale). */
#ifdef KDRT_DOUBLE
#define KDRT_BOX_FAR_SCALE (1.0 + 4.0 * DBL_EPSILON)
#else
#define KDRT_BOX_FAR_SCALE (1.0f + 4.0f * FLT_EPSILON)
#endif

/* The ray as the box tests use it: per axis the row of its near planes
 * (1: the upper bounds, for a negative reciprocal), the origin, the
 * reciprocal, and for the far planes the reciprocal times the factor. */
typedef struct BvhRay {
    int near[3];
    real org[3], inv_near[3], inv_far[3];
} BvhRay;

inline BvhRay bvh_ray(const Ray* ray) {
    BvhRay r;
    const real org[3] = {ray->org.x, ray->org.y, ray->org.z};
    const real inv[3] = {ray->inv_dir.x, ray->inv_dir.y, ray->inv_dir.z};
#pragma unroll /* BvhRay's arrays indexed by constants: kept in registers (see BvhNodeRows) */
    for (int a = 0; a < 3; ++a) {
        r.near[a] = inv[a] < R(0) ? 1 : 0;
        r.org[a] = org[a];
        r.inv_near[a] = inv[a];
        r.inv_far[a] = inv[a] * (real)KDRT_BOX_FAR_SCALE;
    }
    return r;
}

/* Where visiting stops: beyond done_at plus the termination slack. */
inline real bvh_limit(const Ray* ray, real done_at) { return done_at + termination_slack(ray, done_at); }

#ifdef KDRT_CPU_DEVICE

#ifdef KDRT_DOUBLE
typedef double8 real8;
typedef long8 mask8;
#define KDRT_BOX_ROW(p) convert_double8(vload8(0, (p)))
#else
typedef float8 real8;
typedef int8 mask8;
#define KDRT_BOX_ROW(p) vload8(0, (p))
#endif

/* lane_bits (common.cl) of eight lanes: one movmskps of a float8 with AVX,
 * else the two halves'. */
#if defined(__clang__) && defined(__has_builtin)
#if __has_builtin(__builtin_ia32_movmskps256) && defined(__AVX__) && !defined(KDRT_DOUBLE)
#define KDRT_MOVMSKPS256
#endif
#endif
#ifdef KDRT_MOVMSKPS256
inline uint lane_bits8(mask8 m) { return (uint)__builtin_ia32_movmskps256(as_float8(m)); }
#else
inline uint lane_bits8(mask8 m) { return lane_bits(m.lo) | (lane_bits(m.hi) << 4); }
#endif

/* The rows of the node's eight boxes a ray whose near planes are `near`
 * (BvhRay's) meets: the near planes and the far, per axis. The axes' loops
 * here and below are unrolled (as is bvh_ray's): PoCL 3.1's compiler keeps
 * them loops otherwise, with the six distance rows and the ray's fields
 * going through memory at every node. */
typedef struct BvhNodeRows {
    real8 near_row[3], far_row[3];
} BvhNodeRows;

inline BvhNodeRows bvh_node_rows(__global const GpuBvhNode* node, const int* near) {
    BvhNodeRows p;
#pragma unroll
    for (int a = 0; a < 3; ++a) {
        p.near_row[a] = KDRT_BOX_ROW(node->box[near[a]][a]);
        p.far_row[a] = KDRT_BOX_ROW(node->box[1 - near[a]][a]);
    }
    return p;
}

/* Which of the eight boxes of `p` the ray enters within [0, limit] (bit i:
 * slot i), and where (t_enter): bvh_box_hits of the twin, a plane of all
 * eight boxes per vector operation. select(b, a, a > b) is the twin's
 * a > b ? a : b lane by lane. */
inline uint bvh_box_hits(const BvhNodeRows* p, const BvhRay* r, real limit, real* t_enter) {
    real8 tn[3], tf[3];
#pragma unroll
    for (int a = 0; a < 3; ++a) {
        const real8 org = (real8)(r->org[a]);
        tn[a] = (p->near_row[a] - org) * (real8)(r->inv_near[a]);
        tf[a] = (p->far_row[a] - org) * (real8)(r->inv_far[a]);
    }
    const real8 zero = (real8)(R(0)), lim = (real8)(limit);
    const real8 n01 = select(tn[1], tn[0], tn[0] > tn[1]);
    const real8 n2 = select(zero, tn[2], tn[2] > zero);
    const real8 f01 = select(tf[1], tf[0], tf[0] < tf[1]);
    const real8 f2 = select(lim, tf[2], tf[2] < lim);
    const real8 t_in = select(n2, n01, n01 > n2);
    const real8 t_out = select(f2, f01, f01 < f2);
    vstore8(t_in, 0, t_enter);
    return lane_bits8(t_in <= t_out);
}

/* Which of the node's eight boxes the ray enters within [0, limit], and where:
 * bvh_node_hits of the twin. */
inline uint bvh_node_hits(__global const GpuBvhNode* node, const BvhRay* r, real limit, real* t_enter) {
    const BvhNodeRows p = bvh_node_rows(node, r->near);
    return bvh_box_hits(&p, r, limit, t_enter);
}

/* Starts the loads of the data of the node's `hits` children, as the twin's
 * prefetch_children: the nodes themselves for inner slots; for leaf slots,
 * their first block in the packed copy, else their list of object ids (whose
 * objects visit_objects then prefetches). The first is visited now, the
 * others later, and their data is on its way meanwhile. */
inline void bvh_prefetch_children(const Scene* scene, __global const GpuBvhNode* node, uint hits) {
    for (; hits != 0u; hits &= hits - 1u) {
        const uint s = lowest_lane(hits);
        const uint child = node->child[s], count = node->count[s];
        if ((count & KDRT_BVH_LEAF_FLAG) == 0u) {
            prefetch_lines((__global const uchar*)&scene->bvh_nodes[child], (uint)sizeof(GpuBvhNode));
            continue;
        }
#ifdef KDRT_PACKED_LEAVES
        if (scene->packed) {
            if ((count & KDRT_BVH_LEAF_RECORD) == 0u)
                prefetch_lines((__global const uchar*)&scene->leaf_blocks[child], (uint)sizeof(LeafBlockRec));
            continue;
        }
#endif
        KDRT_PREFETCH(scene->leaf_objects + child);
    }
}

/* A leaf slot's objects: leaf_objects[child ..], or where the nodes are the
 * packed copy (Scene.packed), its blocks or its record (KDRT_BVH_LEAF_RECORD). */
inline real visit_bvh_leaf(const Scene* scene, const Ray* ray, uint child, uint count, bool any_hit, real t_max,
                           Mailbox* tested, Hit* best) {
#ifdef KDRT_PACKED_LEAVES
    if (scene->packed) {
        GpuPackedLeaf leaf;
        if ((count & KDRT_BVH_LEAF_RECORD) != 0u) {
            leaf = scene->packed_leaves[child];
        } else {
            leaf.first_block = child;
            leaf.block_count = count & ~KDRT_BVH_LEAF_FLAG;
            leaf.first_sphere = 0u;
            leaf.sphere_count = 0u;
        }
        return visit_packed_leaf(scene, ray, leaf, any_hit, t_max, tested, best);
    }
#endif
    return visit_range(scene, ray, child, count & ~KDRT_BVH_LEAF_FLAG, any_hit, t_max, tested, best);
}

/* A slot's reference (child, count) and where the ray enters its box. */
typedef struct BvhEntry {
    uint child, count;
    real t;
} BvhEntry;

inline BvhEntry bvh_entry(__global const GpuBvhNode* node, uint slot, real t) {
    BvhEntry e;
    e.child = node->child[slot];
    e.count = node->count[slot];
    e.t = t;
    return e;
}

KDRT_INLINE void traverse(const Scene* scene, const Ray* ray, real t_max, bool any_hit, Hit* best) {
    const BvhRay r = bvh_ray(ray);
    real limit = bvh_limit(ray, t_max);
    Mailbox tested;
    clear_mailbox(&tested);
    BvhEntry stack[KDRT_BVH_SORTED_STACK_SIZE];
    int top = 0;
    BvhEntry cur;
    cur.child = 0u;
    cur.count = 0u;
    cur.t = R(0);
    for (;;) {
        if ((cur.count & KDRT_BVH_LEAF_FLAG) == 0u) {
            __global const GpuBvhNode* node = &scene->bvh_nodes[cur.child];
            real t_enter[KDRT_BVH_WIDTH];
            uint hits = bvh_node_hits(node, &r, limit, t_enter);
            bvh_prefetch_children(scene, node, hits);
            if (hits != 0u) {
                const uint i = lowest_lane(hits);
                hits &= hits - 1u;
                if (hits == 0u) { /* one child: straight on */
                    cur = bvh_entry(node, i, t_enter[i]);
                    continue;
                }
                /* The twin's take_children, written out: PoCL makes slower code of a
                 * helper that takes the stack by pointer. */
                if (any_hit) { /* the first now, the others in turn (the twin's ChildOrder::AsStored) */
                    cur = bvh_entry(node, i, t_enter[i]);
                    for (; hits != 0u; hits &= hits - 1u) {
                        const uint k = lowest_lane(hits);
                        stack[top++] = bvh_entry(node, k, t_enter[k]);
                    }
                    continue;
                }
                const uint j = lowest_lane(hits);
                hits &= hits - 1u;
                BvhEntry a = bvh_entry(node, i, t_enter[i]), b = bvh_entry(node, j, t_enter[j]);
                if (a.t < b.t) {
                    const BvhEntry tmp = a;
                    a = b;
                    b = tmp;
                }
                if (hits == 0u) { /* two: the farther waits */
                    stack[top++] = a;
                    cur = b;
                    continue;
                }
                /* More: all on the stack, sorted so that the nearest is on top. */
                const int first = top;
                stack[top++] = a;
                stack[top++] = b;
                for (; hits != 0u; hits &= hits - 1u) {
                    const uint k = lowest_lane(hits);
                    const BvhEntry e = bvh_entry(node, k, t_enter[k]);
                    int at = top++;
                    while (at > first && stack[at - 1].t < e.t) {
                        stack[at] = stack[at - 1];
                        --at;
                    }
                    stack[at] = e;
                }
                cur = stack[--top];
                continue;
            }
        } else if (cur.count != KDRT_BVH_LEAF_FLAG) {
            const real done_at = visit_bvh_leaf(scene, ray, cur.child, cur.count, any_hit, t_max, &tested, best);
            if (!(done_at >= R(0))) return; /* -inf: an any-hit query is satisfied */
            const real l = bvh_limit(ray, done_at);
            limit = l < limit ? l : limit;
        }
        /* The nearest pending entry that still matters. */
        for (;;) {
            if (top == 0) return;
            cur = stack[--top];
            if (cur.t <= limit) break;
        }
    }
}

#else /* GPUs */

/* Where the ray enters a slot's box (its halves lo, hi: bvh_slot_half): the
 * largest of its three near distances and 0, as pairs, with the twin's
 * selects (a NaN loses). */
inline real bvh_box_entry(float4 lo, float4 hi, const BvhRay* r) {
    const real t0 = ((real)(r->near[0] ? hi.x : lo.x) - r->org[0]) * r->inv_near[0];
    const real t1 = ((real)(r->near[1] ? hi.y : lo.y) - r->org[1]) * r->inv_near[1];
    const real t2 = ((real)(r->near[2] ? hi.z : lo.z) - r->org[2]) * r->inv_near[2];
    const real n01 = t0 > t1 ? t0 : t1;
    const real n2 = t2 > R(0) ? t2 : R(0);
    return n01 > n2 ? n01 : n2;
}

inline real bvh_slot_entry(__global const GpuBvhNode* node, const BvhRay* r, uint s) {
    return bvh_box_entry(bvh_slot_half(node, s, 0u), bvh_slot_half(node, s, 1u), r);
}

/* Whether the ray enters the slot's box within [0, limit], and where. */
inline bool bvh_slot_hit(float4 lo, float4 hi, const BvhRay* r, real limit, real* t_enter) {
    const real t_in = bvh_box_entry(lo, hi, r);
    const real f0 = ((real)(r->near[0] ? lo.x : hi.x) - r->org[0]) * r->inv_far[0];
    const real f1 = ((real)(r->near[1] ? lo.y : hi.y) - r->org[1]) * r->inv_far[1];
    const real f2 = ((real)(r->near[2] ? lo.z : hi.z) - r->org[2]) * r->inv_far[2];
    const real f01 = f0 < f1 ? f0 : f1;
    const real f2l = f2 < limit ? f2 : limit;
    const real t_out = f01 < f2l ? f01 : f2l;
    *t_enter = t_in;
    return t_in <= t_out;
}

/* Which of the node's used slots the ray enters within [0, limit] (bit s:
 * slot s), and where (t_enter[s]). */
inline uint bvh_slots_hit(__global const GpuBvhNode* node, const BvhRay* r, real limit, real* t_enter) {
    uint hits = 0u;
    for (uint s = 0; s < KDRT_BVH_WIDTH; ++s) {
        const float4 lo = bvh_slot_half(node, s, 0u), hi = bvh_slot_half(node, s, 1u);
        if (as_uint(hi.w) == KDRT_BVH_LEAF_FLAG) break; /* empty slots: after the used ones, never hit */
        if (bvh_slot_hit(lo, hi, r, limit, &t_enter[s])) hits |= 1u << s;
    }
    return hits;
}

/* The node's hit slots in the order the twin's sorted stack pops them:
 * nearer first, and of two at the same distance the higher slot (pushed
 * later); as a list of slot + 1, four bits each, the first lowest. */
inline uint bvh_visit_order(uint hits, const real* t_enter) {
    uint list = 0u;
    for (uint h = hits; h != 0u; h &= h - 1u) { /* the hit slots alone */
        const uint s = lowest_lane(h);
        uint rank = 0u;
        for (uint g = hits; g != 0u; g &= g - 1u) {
            const uint k = lowest_lane(g);
            if (t_enter[k] < t_enter[s] || (t_enter[k] == t_enter[s] && k > s)) ++rank;
        }
        list |= (s + 1u) << (4u * rank);
    }
    return list;
}

KDRT_INLINE void traverse(const Scene* scene, const Ray* ray, real t_max, bool any_hit, Hit* best) {
    const BvhRay r = bvh_ray(ray);
    real limit = bvh_limit(ray, t_max);
    Mailbox tested;
    clear_mailbox(&tested);
    uint stack_node[KDRT_BVH_SLOT_STACK_SIZE], stack_slots[KDRT_BVH_SLOT_STACK_SIZE];
    int top = 0;
    uint child = 0u, count = 0u; /* the slot reference being visited: the root first */
    for (;;) {
        if ((count & KDRT_BVH_LEAF_FLAG) == 0u) {
            __global const GpuBvhNode* node = &scene->bvh_nodes[child];
            real t_enter[KDRT_BVH_WIDTH];
            const uint hits = bvh_slots_hit(node, &r, limit, t_enter);
            if (hits != 0u) {
                uint list = bvh_visit_order(hits, t_enter);
                const uint s = (list & 15u) - 1u;
                list >>= 4;
                if (list != 0u) { /* the others wait, with their node */
                    stack_node[top] = child;
                    stack_slots[top] = list;
                    ++top;
                }
                child = bvh_child(node, s);
                count = bvh_count(node, s);
                continue;
            }
        } else if (count != KDRT_BVH_LEAF_FLAG) {
            const real done_at = visit_range(scene, ray, child, count & ~KDRT_BVH_LEAF_FLAG, any_hit, t_max, &tested, best);
            if (!(done_at >= R(0))) return; /* -inf: an any-hit query is satisfied */
            const real l = bvh_limit(ray, done_at);
            limit = l < limit ? l : limit;
        }
        /* The nearest pending slot that still matters. */
        for (;;) {
            if (top == 0) return;
            const uint n = stack_node[top - 1];
            const uint list = stack_slots[top - 1];
            const uint s = (list & 15u) - 1u;
            if ((list >> 4) != 0u) stack_slots[top - 1] = list >> 4;
            else --top;
            __global const GpuBvhNode* node = &scene->bvh_nodes[n];
            if (bvh_slot_entry(node, &r, s) <= limit) {
                child = bvh_child(node, s);
                count = bvh_count(node, s);
                break;
            }
        }
    }
}

#endif
#endif
