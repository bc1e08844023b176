/* traverse_common.cl: what the traversals share, the twin of
 * libkdrt/src/cpu/traversal_common.h. */

inline bool kd_is_leaf(KdNode n) { return (n.word1 & 3u) == KDRT_LEAF_FLAG; }
inline int kd_axis(KdNode n) { return (int)(n.word1 & 3u); }
inline uint kd_above_child(KdNode n) { return n.word1 >> 2; }
inline real kd_split(KdNode n) { return (real)as_float(n.word0); }

/* Stop only when the best hit is clearly inside the leaf: see the C++ twin. */
inline real termination_slack(const Ray* ray, real t) {
    return KDRT_SLACK_EPS * fmax(ray->org_max, fabs(t));
}

inline bool leaf_finishes(const Ray* ray, real done_at, real t_exit) {
    return done_at < t_exit - termination_slack(ray, t_exit);
}

#ifdef KDRT_CPU_DEVICE
/* The loop below on the three axes at once, for CPU devices, where picking
 * each axis through get3's selects is costly. The same values: a flat axis is one that the loop skips (its near and far
 * made -inf and +inf), the swap is the loop's compare, and fmax and fmin
 * give the loop's results in any order, NaN operands included. */
inline bool clip_to_box(const Scene* scene, const Ray* ray, real t_max, real* t0, real* t1) {
    const real3 o = ray->org, inf = (real3)(REAL_INF);
    const real3 lo = scene->box_min, hi = scene->box_max;
    const mask3 flat = ray->dir == (real3)(R(0));
    if (any(flat & ((o < lo) | (o > hi)))) return false;
    const real3 tn = (lo - o) * ray->inv_dir, tf = (hi - o) * ray->inv_dir;
    const mask3 swap = tn > tf;
    const real3 near = select(select(tn, tf, swap), -inf, flat), far = select(select(tf, tn, swap), inf, flat);
    *t0 = fmax(fmax(fmax(R(0), near.x), near.y), near.z);
    *t1 = fmin(fmin(fmin(t_max, far.x), far.y), far.z);
    return *t0 <= *t1;
}
#else
inline bool clip_to_box(const Scene* scene, const Ray* ray, real t_max, real* t0, real* t1) {
    *t0 = R(0);
    *t1 = t_max;
    for (int a = 0; a < 3; ++a) {
        const real lo = get3(scene->box_min, a), hi = get3(scene->box_max, a);
        const real o = get3(ray->org, a), d = get3(ray->dir, a);
        if (d == R(0)) {
            if (o < lo || o > hi) return false;
            continue;
        }
        real tn = (lo - o) * get3(ray->inv_dir, a);
        real tf = (hi - o) * get3(ray->inv_dir, a);
        if (tn > tf) {
            real tmp = tn;
            tn = tf;
            tf = tmp;
        }
        *t0 = fmax(*t0, tn);
        *t1 = fmin(*t1, tf);
    }
    return *t0 <= *t1;
}
#endif

/* Near and far child at an inner node, and the split plane's t (+inf when the
 * ray runs parallel to it; a ray lying in the plane takes the lower side).
 * The ray comes as the values the traversal holds (ray_axes): picking the
 * node axis' component of values loaded through a Ray pointer, LLVM's x86
 * back end branches on the axis, which changes from node to node (PoCL:
 * about a mispredicted branch per node, and twice the branches). */
inline real split_step(const Scene* scene, uint node, real3 org, real3 dir, real3 inv_dir, uint* near_child,
                       uint* far_child) {
    const KdNode n = scene->nodes[node];
    const int axis = kd_axis(n);
    const real split = kd_split(n);
    const real o = get3(org, axis), d = get3(dir, axis);
    const uint below = node + 1, above = kd_above_child(n);
    /* The below child is the next node, most likely in the same cache line; fetch the other early. */
    KDRT_PREFETCH(&scene->nodes[above]);
    const bool below_first = d > R(0) || (d == R(0) && o <= split);
    *near_child = below_first ? below : above;
    *far_child = below_first ? above : below;
    return d == R(0) ? REAL_INF : (split - o) * get3(inv_dir, axis);
}

/* A leaf's objects leaf_objects[first .. first + count), through the packed
 * leaves where the scene takes them (Scene.packed: a kd-tree's leaf or a BVH's). */
inline real visit_range(const Scene* scene, const Ray* ray, uint first, uint count, bool any_hit, real t_max,
                        Mailbox* tested, Hit* best) {
#ifdef KDRT_PACKED_LEAVES
    /* An empty leaf's first may be past the lists. */
    if (scene->packed)
        return count == 0u ? (any_hit ? REAL_INF : best->t)
                           : visit_packed_leaf(scene, ray, scene->packed_leaves[first], any_hit, t_max, tested, best);
#endif
    return visit_objects(scene, ray, scene->leaf_objects + first, count, any_hit, t_max, tested, best);
}

/* The leaf node holds its list's range (first, count): no leaf record to load. */
inline real visit_leaf(const Scene* scene, KdNode n, const Ray* ray, bool any_hit, real t_max, Mailbox* tested,
                       Hit* best) {
    return visit_range(scene, ray, n.word0, n.word1 >> 2, any_hit, t_max, tested, best);
}
