/* bvh_node.cl: a wide BVH node's slots as each kind of device holds them
 * (kernel_records.h). CPU devices keep GpuBvhNode's rows, which their walks
 * read eight slots at a time; GPUs get GpuBvhSlot, a slot's box and reference
 * in two 16-byte loads. Code that runs on both reads a slot through these. */

#ifdef KDRT_CPU_DEVICE
inline float bvh_bound(__global const GpuBvhNode* node, uint side, uint axis, uint s) { return node->box[side][axis][s]; }
inline uint bvh_child(__global const GpuBvhNode* node, uint s) { return node->child[s]; }
inline uint bvh_count(__global const GpuBvhNode* node, uint s) { return node->count[s]; }
#else
/* Half `side` of slot s: (lower bounds, child) for 0, (upper bounds, count)
 * for 1. Buffers start aligned far beyond 16 bytes, and a node is 256. */
inline float4 bvh_slot_half(__global const GpuBvhNode* node, uint s, uint side) {
    return ((__global const float4*)node)[2u * s + side];
}
inline float bvh_bound(__global const GpuBvhNode* node, uint side, uint axis, uint s) {
    __global const GpuBvhSlot* slot = (__global const GpuBvhSlot*)node + s;
    return side == 0u ? slot->lo[axis] : slot->hi[axis];
}
inline uint bvh_child(__global const GpuBvhNode* node, uint s) { return ((__global const GpuBvhSlot*)node)[s].child; }
inline uint bvh_count(__global const GpuBvhNode* node, uint s) { return ((__global const GpuBvhSlot*)node)[s].count; }
#endif
