/* traverse_bvh_packet.cl: four rays through the wide BVH together, the twin
 * of traverse_bvh_packet (libkdrt/src/cpu/traverse_bvh.h). CPU devices only
 * (KDRT_CPU_DEVICE), as the kd-tree's packet (traverse_packet.cl, whose
 * trace_lanes calls this one's traverse_packet): four coherent rays share
 * the walk's node loads, its stack and its order.
 *
 * Each lane tests the node's eight boxes as traverse() does, on rows loaded
 * once for all four (bvh_packet_node_hits), and keeps its own limit; the
 * children some lane reached go on one stack, nearest first by the least
 * entry of their lanes (any-hit walks: pushed in slot order, unsorted, so
 * the highest slot first: the twin's ChildOrder::AsStored), with each lane's
 * entry distance, and a popped child is visited by the lanes whose entry is
 * within their limit. Leaves are tested lane by lane (visit_bvh_leaf). A
 * lane may meet its leaves in another order than alone, which changes no
 * closest hit (closer_than breaks ties), no shadow ray's answer and no
 * any-hit query's (stopped_past_end in ray_query.cl).
 *
 * The stack: KDRT_BVH_SORTED_STACK_SIZE entries of four entry distances,
 * the child, its count, its lanes and their nearest entry (14368 bytes in
 * float, 25144 in double, on the thread's stack under PoCL). */
#if defined(KDRT_PACKETS) && KDRT_TRAVERSAL == KDRT_TRAVERSAL_BVH

typedef struct BvhPacketEntry {
    real t[4];       /* where each lane enters the box; +inf in lanes that did not reach it */
    uint child, count; /* the slot's reference */
    uint lanes;      /* the lanes that reached it */
    real nearest;    /* the least of their entries: the order */
} BvhPacketEntry;

/* bvh_node_hits for the four lanes in `lanes`, whose rays share their
 * direction signs (packet_compatible): the node's six rows are loaded once
 * for all of them. Lanes not in `lanes` hit nothing. Forced inline: PoCL
 * 3.1 keeps it a call otherwise, with the lanes' results through memory. */
KDRT_INLINE uint bvh_packet_node_hits(__global const GpuBvhNode* node, const BvhRay* r, uint lanes, const real* limit,
                                      real (*t_enter)[KDRT_BVH_WIDTH], uint* hits) {
    const BvhNodeRows p = bvh_node_rows(node, r[0].near);
    uint reached = 0u;
#pragma unroll
    for (int k = 0; k < 4; ++k) {
        hits[k] = ((lanes >> k) & 1u) != 0u ? bvh_box_hits(&p, &r[k], limit[k], t_enter[k]) : 0u;
        reached |= hits[k];
    }
    return reached;
}

/* traverse() for the lanes in `valid` of packet_compatible rays, lane by
 * lane: closest hits into best[i], or with any_hit a hit nearer than
 * t_max[i] (a lane then stops, its best nearer than t_max). */
inline void traverse_packet(const Scene* scene, const Ray* rays, uint valid, const real* t_max, bool any_hit,
                            Hit* best) {
    BvhRay r[4];
    real limit[4];
    Mailbox tested[4];
    for (int k = 0; k < 4; ++k) {
        best[k] = no_hit();
        r[k] = bvh_ray(&rays[k]);
        limit[k] = ((valid >> k) & 1u) != 0u ? bvh_limit(&rays[k], t_max[k]) : -REAL_INF; /* t_max: unset there */
        clear_mailbox(&tested[k]);
    }
    BvhPacketEntry stack[KDRT_BVH_SORTED_STACK_SIZE];
    int top = 0;
    /* The slot being visited and the lanes that visit it: the root first. */
    uint child = 0u, count = 0u, lanes = valid;
    uint live = valid; /* the lanes whose any-hit query is not yet satisfied */
    for (;;) {
        if ((count & KDRT_BVH_LEAF_FLAG) == 0u) {
            __global const GpuBvhNode* node = &scene->bvh_nodes[child];
            real t_enter[4][KDRT_BVH_WIDTH];
            uint hits[4];
            uint reached = bvh_packet_node_hits(node, r, lanes, limit, t_enter, hits);
            bvh_prefetch_children(scene, node, reached);
            /* The children some lane reached, on the stack with the nearest
             * (any-hit walks: the highest slot) on top. Each entry is written
             * in place and its distances as one vector, which the pop below
             * loads as one: an entry built aside and copied whole, or lanes
             * stored one by one and loaded as a vector, would wait for the
             * stores instead of forwarding them. */
            const int first = top;
            for (; reached != 0u; reached &= reached - 1u) {
                const uint c = lowest_lane(reached);
                const uint in = ((hits[0] >> c) & 1u) | (((hits[1] >> c) & 1u) << 1) |
                                (((hits[2] >> c) & 1u) << 2) | (((hits[3] >> c) & 1u) << 3);
                const mask4 lanes_in = ((mask4)(in) & (mask4)(1, 2, 4, 8)) != (mask4)(0);
                const real4 t = select((real4)(REAL_INF),
                                       (real4)(t_enter[0][c], t_enter[1][c], t_enter[2][c], t_enter[3][c]), lanes_in);
                const real n01 = t.x < t.y ? t.x : t.y, n23 = t.z < t.w ? t.z : t.w;
                const real nearest = n01 < n23 ? n01 : n23;
                int j = top++;
                while (!any_hit && j > first && stack[j - 1].nearest < nearest) {
                    stack[j] = stack[j - 1];
                    --j;
                }
                vstore4(t, 0, stack[j].t);
                stack[j].child = node->child[c];
                stack[j].count = node->count[c];
                stack[j].lanes = in;
                stack[j].nearest = nearest;
            }
        } else if (count != KDRT_BVH_LEAF_FLAG) {
            for (uint m = lanes; m != 0u; m &= m - 1u) {
                const uint k = lowest_lane(m);
                const real done_at =
                    visit_bvh_leaf(scene, &rays[k], child, count, any_hit, t_max[k], &tested[k], &best[k]);
                /* -inf: an any-hit query is satisfied, and the lane enters no box again. */
                const bool satisfied = !(done_at >= R(0));
                const real l = satisfied ? -REAL_INF : bvh_limit(&rays[k], done_at);
                limit[k] = l < limit[k] ? l : limit[k];
                if (satisfied) live &= ~(1u << k);
            }
            if (live == 0u) return; /* every lane satisfied: nothing on the stack matters */
        }
        /* The next pending entry (the nearest, unless any_hit) that still
         * matters to some lane. */
        for (;;) {
            if (top == 0) return;
            --top;
            lanes = stack[top].lanes & lane_bits(vload4(0, stack[top].t) <= vload4(0, limit));
            if (lanes != 0u) break;
        }
        child = stack[top].child;
        count = stack[top].count;
    }
}

#endif
