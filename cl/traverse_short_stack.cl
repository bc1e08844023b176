/* traverse_short_stack.cl: a ring buffer of KDRT_SHORT_STACK_SIZE entries that
 * drops its oldest entry when full, kd-restart with push-down when it runs dry
 * (Horn et al. 2007); the twin of libkdrt/src/cpu/traverse_short_stack.h. */
#if KDRT_TRAVERSAL == 4
KDRT_INLINE void traverse(const Scene* scene, const Ray* ray, real t_max, bool any_hit, Hit* best) {
    real t0, t1;
    if (!clip_to_box(scene, ray, t_max, &t0, &t1)) return;
    const real3 org = ray->org, dir = ray->dir, inv_dir = ray->inv_dir; /* held for split_step */
    Mailbox tested;
    clear_mailbox(&tested);
    uint stack_node[KDRT_SHORT_STACK_SIZE];
    real stack_tmin[KDRT_SHORT_STACK_SIZE], stack_tmax[KDRT_SHORT_STACK_SIZE];
    int top = 0, count = 0; /* next free slot (modulo the size), entries held */
    uint node = 0, restart_node = 0;
    bool push_down = true; /* no push since the last (re)start: node's cell holds all of [tmin, t1] */
    real tmin = t0, tmax = t1;
    for (;;) {
        const KdNode n = scene->nodes[node];
        if (!kd_is_leaf(n)) {
            uint near_child, far_child;
            const real t_split = split_step(scene, node, org, dir, inv_dir, &near_child, &far_child);
            if (t_split <= tmin) {
                node = far_child;
            } else if (t_split >= tmax) {
                node = near_child;
            } else {
                stack_node[top] = far_child;
                stack_tmin[top] = t_split;
                stack_tmax[top] = tmax;
                top = top + 1 == KDRT_SHORT_STACK_SIZE ? 0 : top + 1;
                count = count < KDRT_SHORT_STACK_SIZE ? count + 1 : KDRT_SHORT_STACK_SIZE;
                node = near_child;
                tmax = t_split;
                push_down = false;
            }
            if (push_down) restart_node = node;
            continue;
        }
        if (leaf_finishes(ray, visit_leaf(scene, n, ray, any_hit, t_max, &tested, best), tmax)) return;
        if (count == 0) {
            if (tmax >= t1) return;
            node = restart_node; /* entries were dropped: kd-restart behind this leaf */
            tmin = tmax;
            tmax = t1;
            push_down = true;
            continue;
        }
        top = top == 0 ? KDRT_SHORT_STACK_SIZE - 1 : top - 1;
        --count;
        node = stack_node[top];
        tmin = stack_tmin[top];
        tmax = stack_tmax[top];
    }
}
#endif
