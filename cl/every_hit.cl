/* every_hit.cl: every hit of a ray query in its window (kdrt::count_hits,
 * kdrt::all_hits), the twin of Tracer::every in libkdrt/src/cpu/tracer.h:
 * each triangle hit, each sphere root, inside (max(t_min, 0), t_max], with
 * the setup and window of ray_query.cl.
 *
 * Every hit needs no order and no early exit, so one walk of each structure
 * serves every program: the kd-tree's cells along the ray with a stack (any
 * kd traversal's program; the same cells the traversals visit), the BVH's
 * hit boxes with one stack entry per node on the path, or every object. The
 * render's traversals are left as they are.
 *
 * A kd-tree references an object from every leaf it overlaps, so a ray may
 * meet it several times; the mailbox (KDRT_MAILBOX) drops most repeats and
 * the host the rest (cl_hit_lists.cpp): the kernel reports raw hits, and the
 * same ray and object give the same t in every leaf. Two passes: the first
 * counts each ray's raw hits, the second writes them where the host's prefix
 * sums put them, as QueryHits with internal ids (geometry = the object) and,
 * until the host names them, `primitive` holding which root of a sphere (0
 * near, 1 far; triangles 0): a ray grazing a sphere has two roots at one t. */

/* Where a ray's raw hits go: counted, and with `out` written up to `room`. */
typedef struct HitSink {
    const QuerySetup* s;
    const Ray* ray;     /* the working ray */
    __global QueryHit* out; /* 0: count only */
    uint room;
    uint count;
} HitSink;

/* Object `id` met at working t (root: which of a sphere's), if inside the window. */
inline void sink_hit(const Scene* scene, HitSink* sink, uint id, real t, real b1, real b2, uint root) {
    qreal t_query;
    if (!in_window(sink->s, t, &t_query)) return;
    if (sink->out != 0 && sink->count < sink->room) {
        __global QueryHit* out = &sink->out[sink->count];
        store_query_hit(out, scene, sink->ray, id, t, t_query, b1, b2, 0, 0u);
        out->primitive = root;
    }
    ++sink->count;
}

/* One object's hits: both roots of a sphere, a triangle's one. */
inline void every_object_hit(const Scene* scene, const Ray* ray, uint id, HitSink* sink) {
#ifdef KDRT_HAS_SPHERES
    if (id < scene->sphere_count) {
        __global const SphereRec* sp = &scene->spheres[id];
        real t0, t1;
        if (!sphere_roots(ray, load3(sp->center), sp->radius, &t0, &t1)) return;
        sink_hit(scene, sink, id, t0, R(0), R(0), 0u);
        sink_hit(scene, sink, id, t1, R(0), R(0), 1u);
        return;
    }
#endif
#ifdef KDRT_HAS_TRIANGLES
    real t, b1, b2;
    if (id >= scene->sphere_count && hit_triangle(scene, ray, id, &t, &b1, &b2)) sink_hit(scene, sink, id, t, b1, b2, 0u);
#endif
}

inline void every_leaf_hit(const Scene* scene, const Ray* ray, __global const uint* ids, uint count, Mailbox* tested,
                           HitSink* sink) {
    for (uint i = 0; i < count; ++i)
        if (!mailbox_seen(tested, ids[i])) every_object_hit(scene, ray, ids[i], sink);
}

#if KDRT_TRAVERSAL == 0
inline void every_hit(const Scene* scene, const Ray* ray, real t_max, HitSink* sink) {
    const uint count = scene->sphere_count + scene->triangle_count;
    for (uint id = 0; id < count; ++id) every_object_hit(scene, ray, id, sink);
}

#elif KDRT_TRAVERSAL == KDRT_TRAVERSAL_BVH
/* The boxes of a node the ray enters within [0, limit] (bit s: slot s). */
inline uint every_bvh_slots(__global const GpuBvhNode* node, const BvhRay* r, real limit) {
    real t_enter[KDRT_BVH_WIDTH];
#ifdef KDRT_CPU_DEVICE
    return bvh_node_hits(node, r, limit, t_enter);
#else
    return bvh_slots_hit(node, r, limit, t_enter);
#endif
}

/* Depth first; a stack entry is a node on the path and its hit slots still
 * to visit, so the deepest node's ancestors take one entry each. */
inline void every_hit(const Scene* scene, const Ray* ray, real t_max, HitSink* sink) {
    const BvhRay r = bvh_ray(ray);
    const real limit = bvh_limit(ray, t_max);
    Mailbox tested;
    clear_mailbox(&tested);
    uint stack_node[KDRT_BVH_SLOT_STACK_SIZE], stack_slots[KDRT_BVH_SLOT_STACK_SIZE];
    int top = 0;
    uint node = 0u, slots = every_bvh_slots(&scene->bvh_nodes[0], &r, limit);
    for (;;) {
        if (slots == 0u) {
            if (top == 0) return;
            --top;
            node = stack_node[top];
            slots = stack_slots[top];
        }
        const uint s = lowest_lane(slots);
        slots &= slots - 1u;
        const uint child = bvh_child(&scene->bvh_nodes[node], s), count = bvh_count(&scene->bvh_nodes[node], s);
        if ((count & KDRT_BVH_LEAF_FLAG) != 0u) {
            every_leaf_hit(scene, ray, scene->leaf_objects + child, count & ~KDRT_BVH_LEAF_FLAG, &tested, sink);
            continue;
        }
        if (slots != 0u) {
            stack_node[top] = node;
            stack_slots[top] = slots;
            ++top;
        }
        node = child;
        slots = every_bvh_slots(&scene->bvh_nodes[child], &r, limit);
    }
}

#else
/* The kd-tree's leaves along the ray up to t_max, as traverse_stack.cl
 * visits them but to the end. */
inline void every_hit(const Scene* scene, const Ray* ray, real t_max, HitSink* sink) {
    real t0, t1;
    if (!clip_to_box(scene, ray, t_max, &t0, &t1)) return;
    Mailbox tested;
    clear_mailbox(&tested);
    uint stack_node[KDRT_MAX_TREE_DEPTH + 2];
    real stack_tmin[KDRT_MAX_TREE_DEPTH + 2], stack_tmax[KDRT_MAX_TREE_DEPTH + 2];
    int top = 0;
    uint node = 0;
    real tmin = t0, tmax = t1;
    for (;;) {
        const KdNode n = scene->nodes[node];
        if (!kd_is_leaf(n)) {
            uint near_child, far_child;
            const real t_split = split_step(scene, node, ray->org, ray->dir, ray->inv_dir, &near_child, &far_child);
            if (t_split <= tmin) {
                node = far_child;
            } else if (t_split >= tmax) {
                node = near_child;
            } else {
                stack_node[top] = far_child;
                stack_tmin[top] = t_split;
                stack_tmax[top] = tmax;
                ++top;
                node = near_child;
                tmax = t_split;
            }
            continue;
        }
        every_leaf_hit(scene, ray, scene->leaf_objects + n.word0, n.word1 >> 2, &tested, sink);
        if (top == 0) return;
        --top;
        node = stack_node[top];
        tmin = stack_tmin[top];
        tmax = stack_tmax[top];
    }
}
#endif

/* Ray first + i's raw hits: counted into counts[first + i], and with
 * `write`, stored at hits[offsets[first + i] - base ..], where the host has
 * made room for offsets[first + i + 1] - offsets[first + i] of them. */
__kernel void query_every_hit(KDRT_SCENE_PARAMS, __global const QueryRay* rays, __global uint* counts, uint first,
                              uint count, KDRT_FRAME_PARAMS, __global const ulong* offsets, __global QueryHit* hits,
                              ulong base, uint write) {
    const Scene scene = make_scene(KDRT_SCENE_ARGS, false); /* its walk reads the unpacked nodes and lists */
    const uint i = get_global_id(0);
    if (i >= count) return;
    const QueryRay q = rays[first + i];
    QuerySetup s;
    Ray ray;
    HitSink sink;
    sink.s = &s;
    sink.ray = &ray;
    sink.out = 0;
    sink.room = 0u;
    sink.count = 0u;
    if (write) {
        sink.out = hits + (offsets[first + i] - base);
        sink.room = (uint)(offsets[first + i + 1] - offsets[first + i]);
    }
    if (setup_query(q, query_origin(&q, KDRT_FRAME_ARGS), &s, &ray)) every_hit(&scene, &ray, s.bound, &sink);
    counts[first + i] = sink.count;
}
