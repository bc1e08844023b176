/* closest_point.cl: the point of the scene's surface nearest to each query
 * point (kdrt::closest_points), the twin of closest_point_queries in
 * libkdrt/src/cpu/ray_query_loops.h: a nearest-first search of the kd-tree's
 * cells or the BVH's boxes (libkdrt/src/cpu/traverse_nearest.h), every
 * object without a structure, and the closest point on each primitive met
 * (libkdrt/src/cpu/closest_point.h). The arithmetic is qreal (ray_query.cl):
 * double where the device has it, as on the host, else float. Points come in
 * world space and are taken into the working frame as the rays are. */

inline qreal qdot(qreal3 a, qreal3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline qreal3 qcross(qreal3 x, qreal3 y) {
    return (qreal3)(x.y * y.z - y.y * x.z, x.z * y.x - y.z * x.x, x.x * y.y - y.x * x.y);
}
inline qreal3 qload3(__global const real* p) { return (qreal3)((qreal)p[0], (qreal)p[1], (qreal)p[2]); }

/* The best point so far: squared distance, object, point, barycentrics. */
typedef struct Nearest {
    qreal d2;
    uint id;
    qreal3 point;
    qreal b1, b2;
} Nearest;

/* Ericson, Real-Time Collision Detection 5.1.5: the point of triangle (a, b,
 * c) closest to p by its Voronoi regions, with its barycentrics of b and c. */
inline qreal3 closest_on_triangle(qreal3 p, qreal3 a, qreal3 b, qreal3 c, qreal* v_out, qreal* w_out) {
    const qreal3 ab = b - a, ac = c - a, ap = p - a;
    const qreal d1 = qdot(ab, ap), d2 = qdot(ac, ap);
    *v_out = 0;
    *w_out = 0;
    if (d1 <= 0 && d2 <= 0) return a;
    const qreal3 bp = p - b;
    const qreal d3 = qdot(ab, bp), d4 = qdot(ac, bp);
    *v_out = 1;
    if (d3 >= 0 && d4 <= d3) return b;
    const qreal vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) {
        *v_out = d1 / (d1 - d3);
        return a + *v_out * ab;
    }
    const qreal3 cp = p - c;
    const qreal d5 = qdot(ab, cp), d6 = qdot(ac, cp);
    *v_out = 0;
    *w_out = 1;
    if (d6 >= 0 && d5 <= d6) return c;
    const qreal vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) {
        *w_out = d2 / (d2 - d6);
        return a + *w_out * ac;
    }
    const qreal va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
        *w_out = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        *v_out = 1 - *w_out;
        return b + *w_out * (c - b);
    }
    const qreal denom = 1 / (va + vb + vc);
    *v_out = vb * denom;
    *w_out = vc * denom;
    return a + ab * *v_out + ac * *w_out;
}

/* Object `id`'s closest point to p, into *best when nearer (then the lower id). */
inline void test_nearest(const Scene* scene, qreal3 p, uint id, Nearest* best) {
    Nearest n;
    n.id = id;
    n.b1 = n.b2 = 0;
    if (id < scene->sphere_count) {
        __global const SphereRec* s = &scene->spheres[id];
        const qreal3 c = qload3(s->center), d = p - c;
        const qreal len = sqrt(qdot(d, d));
        /* A query at the centre is equally near every point: take the one towards +x. */
        const qreal3 dir = len > 0 ? d / len : (qreal3)(1, 0, 0);
        n.point = c + (qreal)s->radius * dir;
    } else {
        __global const TriangleRec* t = &scene->triangles[id - scene->sphere_count];
        n.point = closest_on_triangle(p, qload3(t->v0), qload3(t->v1), qload3(t->v2), &n.b1, &n.b2);
    }
    const qreal3 e = n.point - p;
    n.d2 = qdot(e, e);
    if (n.d2 < best->d2 || (n.d2 == best->d2 && n.id < best->id)) *best = n;
}

inline void nearest_in_leaf(const Scene* scene, qreal3 p, __global const uint* ids, uint count, Nearest* best) {
    for (uint i = 0; i < count; ++i) test_nearest(scene, p, ids[i], best);
}

/* Squared distance from p to the box [lo, hi] (0 inside). */
inline qreal box_distance2(qreal3 p, qreal3 lo, qreal3 hi) {
    const qreal3 d = fmax(fmax(lo - p, (qreal3)(0)), p - hi);
    return qdot(d, d);
}

#if KDRT_TRAVERSAL == 0
inline void search_nearest(const Scene* scene, qreal3 p, Nearest* best) {
    const uint count = scene->sphere_count + scene->triangle_count;
    for (uint id = 0; id < count; ++id) test_nearest(scene, p, id, best);
}

#elif KDRT_TRAVERSAL == KDRT_TRAVERSAL_BVH
inline qreal bvh_slot_distance2(__global const GpuBvhNode* node, uint s, qreal3 p) {
    const qreal3 lo = (qreal3)(bvh_bound(node, 0u, 0u, s), bvh_bound(node, 0u, 1u, s), bvh_bound(node, 0u, 2u, s));
    const qreal3 hi = (qreal3)(bvh_bound(node, 1u, 0u, s), bvh_bound(node, 1u, 1u, s), bvh_bound(node, 1u, 2u, s));
    return box_distance2(p, lo, hi);
}

/* A node's used slots no farther than best_d2, nearest first: a list of
 * slot + 1, four bits each, the first lowest (bvh_visit_order's form). */
inline uint nearest_slot_order(__global const GpuBvhNode* node, qreal3 p, qreal best_d2) {
    qreal d2[KDRT_BVH_WIDTH];
    uint used = 0u;
    for (uint s = 0; s < KDRT_BVH_WIDTH && bvh_count(node, s) != KDRT_BVH_LEAF_FLAG; ++s) {
        d2[s] = bvh_slot_distance2(node, s, p);
        if (d2[s] <= best_d2) used |= 1u << s;
    }
    uint list = 0u;
    for (uint u = used; u != 0u; u &= u - 1u) {
        const uint s = lowest_lane(u);
        uint rank = 0u;
        for (uint g = used; g != 0u; g &= g - 1u) {
            const uint k = lowest_lane(g);
            if (d2[k] < d2[s] || (d2[k] == d2[s] && k < s)) ++rank;
        }
        list |= (s + 1u) << (4u * rank);
    }
    return list;
}

/* Depth first, a node's children nearest first; a stack entry is a node on
 * the path and its slots still to visit, each skipped when its box (its
 * distance recomputed) lies farther than the best point found since. */
inline void search_nearest(const Scene* scene, qreal3 p, Nearest* best) {
    uint stack_node[KDRT_BVH_SLOT_STACK_SIZE], stack_slots[KDRT_BVH_SLOT_STACK_SIZE];
    int top = 0;
    uint node = 0u, list = nearest_slot_order(&scene->bvh_nodes[0], p, best->d2);
    for (;;) {
        if (list == 0u) {
            if (top == 0) return;
            --top;
            node = stack_node[top];
            list = stack_slots[top];
        }
        __global const GpuBvhNode* n = &scene->bvh_nodes[node];
        const uint s = (list & 15u) - 1u;
        list >>= 4;
        if (bvh_slot_distance2(n, s, p) > best->d2) continue;
        const uint child = bvh_child(n, s), count = bvh_count(n, s);
        if ((count & KDRT_BVH_LEAF_FLAG) != 0u) {
            nearest_in_leaf(scene, p, scene->leaf_objects + child, count & ~KDRT_BVH_LEAF_FLAG, best);
            continue;
        }
        if (list != 0u) {
            stack_node[top] = node;
            stack_slots[top] = list;
            ++top;
        }
        node = child;
        list = nearest_slot_order(&scene->bvh_nodes[child], p, best->d2);
    }
}

#else
/* A kd-tree cell waiting on the stack: its node and box (floats, as the
 * tree's splits and bounds are; double with KDRT_DOUBLE). */
typedef struct KdCell {
    uint node;
    real lo[3], hi[3];
} KdCell;

inline qreal cell_distance2(qreal3 p, const KdCell* c) {
    return box_distance2(p, (qreal3)(c->lo[0], c->lo[1], c->lo[2]), (qreal3)(c->hi[0], c->hi[1], c->hi[2]));
}

/* Depth first, the child whose cell holds the point first; the other child
 * waits on the stack unless its cell lies farther than the best point. */
inline void search_nearest(const Scene* scene, qreal3 p, Nearest* best) {
    KdCell stack[KDRT_MAX_TREE_DEPTH + 2];
    int top = 0;
    KdCell c;
    c.node = 0u;
    vstore3(scene->box_min, 0, c.lo);
    vstore3(scene->box_max, 0, c.hi);
    stack[top++] = c;
    while (top > 0) {
        c = stack[--top];
        if (cell_distance2(p, &c) > best->d2) continue;
        for (;;) {
            const KdNode n = scene->nodes[c.node];
            if (kd_is_leaf(n)) {
                nearest_in_leaf(scene, p, scene->leaf_objects + n.word0, n.word1 >> 2, best);
                break;
            }
            const int axis = kd_axis(n);
            const real split = kd_split(n);
            KdCell below = c, above = c;
            below.node = c.node + 1u;
            above.node = kd_above_child(n);
            below.hi[axis] = split;
            above.lo[axis] = split;
            const bool point_below = (axis == 0 ? p.x : (axis == 1 ? p.y : p.z)) <= (qreal)split;
            c = point_below ? below : above;
            const KdCell other = point_below ? above : below;
            if (cell_distance2(p, &other) <= best->d2) stack[top++] = other;
        }
    }
}
#endif

/* The query point in the working frame, as query_origin takes a ray's origin. */
#ifdef KDRT_HAS_FP64
inline qreal3 working_point(__global const float* q, double4 frame_origin) {
    return (qreal3)((double)q[0] - frame_origin.x, (double)q[1] - frame_origin.y, (double)q[2] - frame_origin.z);
}
inline float world_coordinate(qreal x, double4 frame_origin, int a) {
    return (float)(x + (a == 0 ? frame_origin.x : (a == 1 ? frame_origin.y : frame_origin.z)));
}
#else
inline qreal3 working_point(__global const float* q, float4 hi, float4 lo) {
    return (qreal3)((q[0] - hi.x) - lo.x, (q[1] - hi.y) - lo.y, (q[2] - hi.z) - lo.z);
}
inline float world_coordinate(qreal x, float4 hi, float4 lo, int a) {
    return (x + (a == 0 ? lo.x : (a == 1 ? lo.y : lo.z))) + (a == 0 ? hi.x : (a == 1 ? hi.y : hi.z));
}
#endif

/* Normalised, with the 2^60 scaling of normalize3 (common.cl). */
inline qreal3 qnormalize(qreal3 v) {
    if (fmax(fabs(v.x), fmax(fabs(v.y), fabs(v.z))) > (qreal)1.152921504606846976e18) v *= (qreal)5.42101086242752217e-20;
    return v * (1 / sqrt(qdot(v, v)));
}

/* The ClosestPoint of the best point n for query point p; internal ids, which the host names. */
inline ClosestPoint closest_point_record(const Scene* scene, const Nearest* n, KDRT_FRAME_PARAMS) {
    ClosestPoint c;
    for (int a = 0; a < 3; ++a) c.point[a] = world_coordinate(a == 0 ? n->point.x : (a == 1 ? n->point.y : n->point.z),
                                                             KDRT_FRAME_ARGS, a);
    c.distance = (float)sqrt(n->d2);
    qreal3 normal;
    c.u = c.v = 0.0f;
    if (n->id < scene->sphere_count) {
        normal = qnormalize(n->point - qload3(scene->spheres[n->id].center));
    } else {
        __global const TriangleRec* t = &scene->triangles[n->id - scene->sphere_count];
        const qreal3 v0 = qload3(t->v0);
        normal = qnormalize(qcross(qload3(t->v1) - v0, qload3(t->v2) - v0));
        c.u = (float)n->b1;
        c.v = (float)n->b2;
    }
    c.normal[0] = (float)normal.x;
    c.normal[1] = (float)normal.y;
    c.normal[2] = (float)normal.z;
    c.object = c.geometry = n->id;
    c.primitive = 0u;
    return c;
}

inline ClosestPoint no_closest_point(void) {
    ClosestPoint c;
    c.point[0] = c.point[1] = c.point[2] = NAN;
    c.distance = INFINITY;
    c.normal[0] = c.normal[1] = c.normal[2] = 0.0f;
    c.u = c.v = 0.0f;
    c.object = c.geometry = c.primitive = KDRT_NO_HIT;
    return c;
}

/* out[first + i]: the closest point to points[3 (first + i) ..] (world space). */
__kernel void query_closest_points(KDRT_SCENE_PARAMS, __global const float* points, __global ClosestPoint* out,
                                   uint first, uint count, KDRT_FRAME_PARAMS) {
    const Scene scene = make_scene(KDRT_SCENE_ARGS, false); /* its walk reads the unpacked nodes and lists */
    const uint i = get_global_id(0);
    if (i >= count) return;
    __global const float* q = points + 3 * (size_t)(first + i);
    out[first + i] = no_closest_point();
    if (!isfinite(q[0]) || !isfinite(q[1]) || !isfinite(q[2])) return;
    if (scene.sphere_count + scene.triangle_count == 0u) return;
    const qreal3 p = working_point(q, KDRT_FRAME_ARGS);
    Nearest best;
    best.d2 = INFINITY;
    best.id = KDRT_NO_HIT;
    search_nearest(&scene, p, &best);
    if (best.id != KDRT_NO_HIT) out[first + i] = closest_point_record(&scene, &best, KDRT_FRAME_ARGS);
}
