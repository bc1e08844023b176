/* traverse_stack.cl: front-to-back traversal with a stack of far children
 * bounded by the tree depth (Jansen 1986; pbrt), the twin of
 * libkdrt/src/cpu/traverse_stack.h. */
#if KDRT_TRAVERSAL == 3
#define KDRT_STACK_SIZE (KDRT_MAX_TREE_DEPTH + 2)
KDRT_INLINE void traverse(const Scene* scene, const Ray* ray, real t_max, bool any_hit, Hit* best) {
    real t0, t1;
    if (!clip_to_box(scene, ray, t_max, &t0, &t1)) return;
    const real3 org = ray->org, dir = ray->dir, inv_dir = ray->inv_dir; /* held for split_step */
    Mailbox tested;
    clear_mailbox(&tested);
    uint stack_node[KDRT_STACK_SIZE];
    real stack_tmin[KDRT_STACK_SIZE], stack_tmax[KDRT_STACK_SIZE];
    int top = 0;
    uint node = 0;
    real tmin = t0, tmax = t1;
    for (;;) {
        const KdNode n = scene->nodes[node];
        if (!kd_is_leaf(n)) {
            uint near_child, far_child;
            const real t_split = split_step(scene, node, org, dir, inv_dir, &near_child, &far_child);
#ifdef KDRT_CPU_DEVICE
            /* Selects, not branches, as in the C++ twin. A GPU keeps the branches:
             * its stack may spill to slow memory, where the
             * store at every step would cost. */
            const bool far_only = t_split <= tmin;
            const bool both = !far_only && !(t_split >= tmax); /* a NaN t_split takes both */
            stack_node[top] = far_child;
            stack_tmin[top] = t_split;
            stack_tmax[top] = tmax;
            top += both ? 1 : 0;
            node = far_only ? far_child : near_child;
            tmax = both ? t_split : tmax;
#else
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
#endif
            continue;
        }
        if (leaf_finishes(ray, visit_leaf(scene, n, ray, any_hit, t_max, &tested, best), tmax)) return;
        if (top == 0) return;
        --top;
        node = stack_node[top];
        tmin = stack_tmin[top];
        tmax = stack_tmax[top];
    }
}
#endif
