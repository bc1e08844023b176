/* traverse_restart.cl: kd-restart (Foley and Sugerman 2005), the study's
 * "basic"; the twin of libkdrt/src/cpu/traverse_restart.h. */
#if KDRT_TRAVERSAL == 1
KDRT_INLINE void traverse(const Scene* scene, const Ray* ray, real t_max, bool any_hit, Hit* best) {
    real t0, t1;
    if (!clip_to_box(scene, ray, t_max, &t0, &t1)) return;
    const real3 org = ray->org, dir = ray->dir, inv_dir = ray->inv_dir; /* held for split_step */
    Mailbox tested;
    clear_mailbox(&tested);
    real t_start = t0;
    for (;;) {
        uint node = 0;
        real tmin = t_start, tmax = t1;
        while (!kd_is_leaf(scene->nodes[node])) {
            uint near_child, far_child;
            const real t_split = split_step(scene, node, org, dir, inv_dir, &near_child, &far_child);
            if (t_split <= tmin) {
                node = far_child;
            } else if (t_split >= tmax) {
                node = near_child;
            } else {
                node = near_child;
                tmax = t_split;
            }
        }
        if (leaf_finishes(ray, visit_leaf(scene, scene->nodes[node], ray, any_hit, t_max, &tested, best), tmax)) return;
        if (tmax >= t1) return;
        t_start = tmax;
    }
}
#endif
