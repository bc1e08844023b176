/* traverse_ropes.cl: stackless traversal over ropes (Havran et al. 1998;
 * Popov et al. 2007), the study's "neighbour"; the twin of
 * libkdrt/src/cpu/traverse_ropes.h. */
#if KDRT_TRAVERSAL == 2
KDRT_INLINE void traverse(const Scene* scene, const Ray* ray, real t_max, bool any_hit, Hit* best) {
    real t0, t1;
    if (!clip_to_box(scene, ray, t_max, &t0, &t1)) return;
    const real3 org = ray->org, dir = ray->dir, inv_dir = ray->inv_dir; /* held for split_step */
    Mailbox tested;
    clear_mailbox(&tested);
    uint node = 0;
    real t_entry = t0;
    /* Each step moves to a cell further along the ray; the cap guards against a corrupt tree only. */
    uint steps_left = scene->leaf_count < 0x3FFFFFF0u ? 4u * scene->leaf_count + 64u : 0xFFFFFFFFu;
    while (steps_left-- > 0u) {
        while (!kd_is_leaf(scene->nodes[node])) {
            uint near_child, far_child;
            const real t_split = split_step(scene, node, org, dir, inv_dir, &near_child, &far_child);
            node = (t_split <= t_entry) ? far_child : near_child;
        }
        const KdNode n = scene->nodes[node];
        __global const KdLeafRopes* r = &scene->ropes[node];
        real t_exit = REAL_INF;
        int face = -1;
        for (int a = 0; a < 3; ++a) {
            const real d = get3(ray->dir, a);
            if (d == R(0)) continue;
            const real plane = (real)(d > R(0) ? r->box_max[a] : r->box_min[a]);
            const real t = (plane - get3(ray->org, a)) * get3(ray->inv_dir, a);
            if (t < t_exit) {
                t_exit = t;
                face = 2 * a + (d > R(0) ? 1 : 0);
            }
        }
        if (leaf_finishes(ray, visit_leaf(scene, n, ray, any_hit, t_max, &tested, best), t_exit)) return;
        if (face < 0 || t_exit >= t1) return;
        const uint next = r->rope[face];
        if (next == KDRT_ROPE_NONE) return;
        node = next;
        t_entry = fmax(t_entry, t_exit);
    }
}
#endif
