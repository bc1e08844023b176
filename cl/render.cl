/* render.cl: the kernels the host launches. Each bounce traces one queue and
 * appends the next bounce's rays to another; the first bounce makes its
 * camera rays itself, in the order the host chose (rows, tiles, Morton),
 * instead of reading them from a queue a kernel of its own wrote. */

/* The region pixel (row * width + column) of the index-th camera ray. GPUs
 * compute rows and tiles as ray_order.cpp lists them, so no table is built
 * and uploaded per frame; other orders come from `order`. CPU devices always
 * read the table (ray_order is then KDRT_PIXEL_ORDER_TABLE): for them the
 * table is a memcpy, and this index arithmetic in the kernel blocks PoCL's
 * vectorisation. */
inline uint pixel_at(__global const uint* order, uint index, uint ray_order, uint width, uint height) {
#ifdef KDRT_CPU_DEVICE
    return order[index];
#else
    if (ray_order == KDRT_PIXEL_ORDER_ROWS) return index;
    if (ray_order != KDRT_PIXEL_ORDER_TILES) return order[index];
    const uint T = KDRT_PIXEL_TILE;
    const uint ty = index / (width * T) * T;  /* the band of T rows (the last may be lower) */
    const uint in_band = index - ty * width;
    const uint band_height = min(T, height - ty);
    const uint tx = in_band / (T * band_height) * T;  /* the tile in the band (the last may be narrower) */
    const uint in_tile = in_band - tx * band_height;
    const uint tile_width = min(T, width - tx);
    return (ty + in_tile / tile_width) * width + tx + in_tile % tile_width;
#endif
}

inline BounceRay camera_ray(CameraRec cam, __global const uint* order, uint index, uint ray_order, real sx, real sy,
                            real weight, uint region_x, uint region_y, uint region_width, uint region_height) {
    const uint pixel = pixel_at(order, index, ray_order, region_width, region_height);
    const uint x = region_x + pixel % region_width, y = region_y + pixel / region_width;
    const real u = (R(2) * ((real)x + sx) / (real)cam.width - R(1)) * cam.tan_half_fov * cam.aspect;
    const real v = (R(1) - R(2) * ((real)y + sy) / (real)cam.height) * cam.tan_half_fov;
    BounceRay r;
    r.org = load3(cam.position);
    r.dir = normalize3(load3(cam.forward) + u * load3(cam.right) + v * load3(cam.up));
    r.weight = (real3)(weight);
    r.ignore = KDRT_NONE_ID;
    r.pixel = pixel;
    return r;
}

#define KDRT_SCENE_PARAMS                                                                                   \
    __global const SphereRec *spheres, __global const TriangleRec *triangles, __global const real *normals,      \
        __global const GpuMaterial *materials, __global const LightRec *lights, __global const KdNode *nodes, \
        __global const uint *leaf_objects, __global const KdLeafRopes *ropes,                                   \
        __global const GpuBvhNode *bvh_nodes, __global const GpuBvhNode *packed_bvh_nodes,                     \
        __global const GpuPackedLeaf *packed_leaves, __global const LeafBlockRec *leaf_blocks,                   \
        __global const uint *leaf_spheres, GpuSceneInfo info

#define KDRT_QUEUE_PARAMS                                                                                      \
    __global const RayRec *in_queue, uint in_first, uint in_count, uint depth, __global RayRec *out_queue, uint out_capacity, \
        __global uint *accum, __global float *rgb, uint rgb_out, __global int *ids, __global float *hit_t,    \
        uint write_ids,                                                                                        \
        volatile __global uint *level_counters, uint slot, uint counted_input, KDRT_CAMERA_PARAMS

/* The camera rays of a batch (depth 1): ray j of the launch is the camera ray
 * of pixel pixel_at(camera_first + j), with the sample's offset and weight.
 * The frame's region [region_x, region_x + region_width) x [region_y, ...):
 * pixels are region pixel indices (row * region_width + column), which are
 * also the rays' and the accumulator's pixel numbers; the direction comes
 * from the frame coordinates, as for the whole frame. */
#define KDRT_CAMERA_PARAMS                                                                                    \
    CameraRec cam, __global const uint *order, uint ray_order, uint camera_first, real sx, real sy, real weight, \
        uint region_x, uint region_y, uint region_width, uint region_height

/* Ray j of this launch's input. */
#define KDRT_INPUT_RAY(j)                                                                                     \
    (depth == 1u ? camera_ray(cam, order, camera_first + (j), ray_order, sx, sy, weight, region_x, region_y,   \
                              region_width, region_height)                                                      \
                 : queued_ray(&in_queue[j]))

/* Three counters per bounce level (slot): [0] rays appended to out_queue,
 * [1] the persistent threads' work counter, [2] shadow rays traced. A
 * chained launch (counted_input) takes at most in_count of the rays that the
 * level before appended, a count the host has not read (cl_frame_renderer.cpp). */
#define KDRT_LAUNCH_COUNTERS                                                                    \
    volatile __global uint *counters = level_counters + 3u * slot;                              \
    if (counted_input && slot > 0u) in_count = min(in_count, level_counters[3u * (slot - 1u)])

#define KDRT_SCENE_ARGS \
    spheres, triangles, normals, materials, lights, nodes, leaf_objects, ropes, bvh_nodes, packed_bvh_nodes,        \
        packed_leaves, leaf_blocks, leaf_spheres, info

/* packed: whether the leaf tests may take the packed leaves, where the
 * program has them (KDRT_PACKED_LEAVES). Renders, closest-hit and any-hit
 * queries do; every-hit and closest-point walks read the unpacked nodes. */
inline Scene make_scene(KDRT_SCENE_PARAMS, bool packed) {
    Scene s;
    s.spheres = spheres;
    s.triangles = triangles;
    s.normals = normals;
    s.materials = materials;
    s.lights = lights;
    s.nodes = nodes;
    s.leaf_objects = leaf_objects;
    s.ropes = ropes;
    s.bvh_nodes = bvh_nodes;
    s.packed_leaves = packed_leaves;
    s.leaf_blocks = leaf_blocks;
    s.leaf_spheres = leaf_spheres;
#ifdef KDRT_PACKED_LEAVES
    s.packed = packed;
#else
    s.packed = false;
#endif
    /* A packed BVH is walked through its packed nodes (leaf slots refer to blocks). */
    if (s.packed) s.bvh_nodes = packed_bvh_nodes;
    s.sphere_count = info.sphere_count;
    s.triangle_count = info.triangle_count;
    s.light_count = info.light_count;
    s.leaf_count = info.leaf_count;
    s.box_min = load3(info.box_min);
    s.box_max = load3(info.box_max);
    s.background = load3(info.background);
    s.ambient = load3(info.ambient);
    return s;
}

/* The pixel's entry a ray's colour goes to once shaded, in accum or with
 * rgb_out in rgb (to_pixel), and its id map entries. The pixels of a launch
 * are scattered over the frame, so each of those writes missed the cache: on
 * PoCL half the time of adding to the sums. Asked for as the ray starts, the
 * lines arrive while it is traced (CPU devices only). */
inline void prefetch_pixel(__global uint* accum, __global float* rgb, uint rgb_out, __global int* ids,
                           __global float* hit_t, uint write_ids, uint pixel) {
    if (rgb_out) {
        KDRT_PREFETCH_WRITE(rgb + 3u * pixel);
        KDRT_PREFETCH_WRITE(rgb + 3u * pixel + 2u);
    } else {
        KDRT_PREFETCH_WRITE(accum + 6u * pixel);
        KDRT_PREFETCH_WRITE(accum + 6u * pixel + 5u);
    }
    if (write_ids) {
        KDRT_PREFETCH_WRITE(ids + pixel);
        KDRT_PREFETCH_WRITE(hit_t + pixel);
    }
}

/* A pixel's share of the frame, c (fixed_colour): added to its sums in
 * accum, or with rgb_out, where it is the whole pixel (one sample, and the
 * only ray of the pixel or its whole tree's sum), written as the image's
 * floats as resolve_image would write them: such a frame needs neither the
 * accumulator's fill nor the resolve. shared: as add_fixed_to_pixel's. */
inline void to_pixel(__global uint* accum, __global float* rgb, uint rgb_out, uint pixel, long3 c, bool shared) {
    if (rgb_out) vstore3(resolved_colour(c), pixel, rgb);
    else add_fixed_to_pixel(accum, pixel, c, shared);
}

/* One work-item per ray. */
__kernel void trace_plain(KDRT_SCENE_PARAMS, KDRT_QUEUE_PARAMS) {
    const Scene scene = make_scene(KDRT_SCENE_ARGS, true);
    KDRT_LAUNCH_COUNTERS;
    const uint i = get_global_id(0);
    if (i >= in_count) return;
    uint shadow_rays = 0;
    Spawned spawned;
    spawned.mask = 0u;
    const BounceRay ray = KDRT_INPUT_RAY(in_first + i);
    const real3 colour = shade_ray(&scene, &ray, depth, &spawned, ids, hit_t, write_ids, &shadow_rays);
    to_pixel(accum, rgb, rgb_out, ray.pixel, fixed_colour(colour), KDRT_PIXEL_SHARED(depth));
    if (spawned.mask) append_spawned(out_queue, out_capacity, atomic_add(&counters[0], popcount(spawned.mask)), &spawned);
    if (shadow_rays) atomic_add(&counters[2], shadow_rays);
}

#ifdef KDRT_PACKETS
#define KDRT_RAYS_PER_ITEM KDRT_PACKETS
#else
#define KDRT_RAYS_PER_ITEM 1
#endif

#define KDRT_QUEUE_ARGS                                                                                       \
    in_queue, in_first, in_count, depth, out_queue, out_capacity, accum, rgb, rgb_out, ids, hit_t, write_ids,   \
        level_counters, slot, counted_input, cam, order, ray_order, camera_first, sx, sy, weight, region_x,     \
        region_y, region_width, region_height

/* A work-item's input rays from i on (KDRT_RAYS_PER_ITEM of them, fewer at
 * the launch's end: returns how many), traced and shaded; ray k's pixel is
 * pixel[k], what it adds to it colour[k], and spawned[k] gets its bounces.
 * With packets, camera rays go together and deeper bounces one after another. */
inline uint shade_input(const Scene* scene, uint i, Spawned* spawned, real3* colour, uint* pixel, uint* shadow_rays,
                        KDRT_QUEUE_PARAMS) {
#ifdef KDRT_PACKETS
    const uint n = min(in_count - i, (uint)KDRT_PACKETS);
    BounceRay rays[KDRT_PACKETS];
    for (uint k = 0; k < n; ++k) {
        rays[k] = KDRT_INPUT_RAY(in_first + i + k);
        pixel[k] = rays[k].pixel;
        prefetch_pixel(accum, rgb, rgb_out, ids, hit_t, write_ids, rays[k].pixel);
    }
    if (depth == 1u) {
        shade_packet(scene, rays, n, depth, spawned, colour, ids, hit_t, write_ids, shadow_rays);
    } else {
        for (uint k = 0; k < n; ++k)
            colour[k] = shade_ray(scene, &rays[k], depth, &spawned[k], ids, hit_t, write_ids, shadow_rays);
    }
    return n;
#else
    const BounceRay ray = KDRT_INPUT_RAY(in_first + i);
    pixel[0] = ray.pixel;
    prefetch_pixel(accum, rgb, rgb_out, ids, hit_t, write_ids, ray.pixel);
    colour[0] = shade_ray(scene, &ray, depth, &spawned[0], ids, hit_t, write_ids, shadow_rays);
    return 1u;
#endif
}

/* Persistent threads (Aila and Laine 2009): just enough work-groups to fill
 * the device; each takes batches of rays from a global counter until the
 * queue is empty, so no group idles behind a slow one. One bounce level per
 * launch (GPUs, and Schedule::Wavefront; CPU devices take trace_trees below).
 * A work-item takes one ray, or on a CPU device with packets (KDRT_PACKETS)
 * four consecutive rays (shade_input; deeper bounces diverge too much for
 * packets, and four rays per work-item amortise the shading on
 * lens than one). */
__kernel void trace_persistent(KDRT_SCENE_PARAMS, KDRT_QUEUE_PARAMS) {
    const Scene scene = make_scene(KDRT_SCENE_ARGS, true);
    __local uint batch_base;
#if KDRT_MAX_DEPTH > 1
    __local uint group_spawned, group_at; /* the group's spawned rays: count, then place in the queue */
#endif
    KDRT_LAUNCH_COUNTERS;
    uint shadow_rays = 0;
    for (;;) {
        if (get_local_id(0) == 0) {
            batch_base = atomic_add(&counters[1], (uint)get_local_size(0) * KDRT_RAYS_PER_ITEM);
#if KDRT_MAX_DEPTH > 1
            group_spawned = 0u;
#endif
        }
        barrier(CLK_LOCAL_MEM_FENCE);
        const uint base = batch_base;
        barrier(CLK_LOCAL_MEM_FENCE);
        if (base >= in_count) break;
        const uint i = base + (uint)get_local_id(0) * KDRT_RAYS_PER_ITEM;
        Spawned spawned[KDRT_RAYS_PER_ITEM];
        for (uint k = 0; k < KDRT_RAYS_PER_ITEM; ++k) spawned[k].mask = 0u;
        if (i < in_count) {
            real3 colour[KDRT_RAYS_PER_ITEM];
            uint pixel[KDRT_RAYS_PER_ITEM];
            const uint n = shade_input(&scene, i, spawned, colour, pixel, &shadow_rays, KDRT_QUEUE_ARGS);
            for (uint k = 0; k < n; ++k)
                to_pixel(accum, rgb, rgb_out, pixel[k], fixed_colour(colour[k]), KDRT_PIXEL_SHARED(depth));
        }
#if KDRT_MAX_DEPTH > 1
        /* The group's spawned rays go to one contiguous range of the queue. */
        uint count = 0u;
        for (uint k = 0; k < KDRT_RAYS_PER_ITEM; ++k) count += popcount(spawned[k].mask);
        uint mine = count ? atomic_add(&group_spawned, count) : 0u;
        barrier(CLK_LOCAL_MEM_FENCE);
        if (get_local_id(0) == 0) group_at = group_spawned ? atomic_add(&counters[0], group_spawned) : 0u;
        barrier(CLK_LOCAL_MEM_FENCE);
        for (uint k = 0; k < KDRT_RAYS_PER_ITEM; ++k)
            if (spawned[k].mask) {
                append_spawned(out_queue, out_capacity, group_at + mine, &spawned[k]);
                mine += popcount(spawned[k].mask);
            }
#endif
    }
    if (shadow_rays) atomic_add(&counters[2], shadow_rays);
}

#if defined(KDRT_CPU_DEVICE) && KDRT_MAX_DEPTH > 1
/* Rays a work-item of trace_trees has yet to trace: a camera packet leaves
 * at most two per ray, and each bounce taken off leaves at most one more
 * (it spawns two; the deepest level spawns none). */
#define KDRT_TREE_STACK (2 * KDRT_RAYS_PER_ITEM + KDRT_MAX_DEPTH)
typedef struct PendingRay {
    BounceRay ray;
    uint depth;
    uint tree; /* the work-item's camera ray it descends from */
} PendingRay;

/* sp's rays onto the stack, read as queued_ray (shade.cl) reads a queue's:
 * written out again because they are in private memory, and OpenCL C 1.2
 * has no generic address space for one function to take both. */
inline void push_spawned(PendingRay* stack, uint* top, const Spawned* sp, uint depth, uint tree) {
    for (uint slot = 0; slot < 2u; ++slot)
        if (sp->mask & (1u << slot)) {
            const RayRec* r = &sp->ray[slot];
            PendingRay* p = &stack[(*top)++];
            p->ray.org = (real3)(r->org[0], r->org[1], r->org[2]);
            p->ray.dir = (real3)(r->dir[0], r->dir[1], r->dir[2]);
            p->ray.weight = (real3)(r->weight[0], r->weight[1], r->weight[2]);
            p->ray.ignore = r->ignore;
            p->ray.pixel = r->pixel;
            p->depth = depth;
            p->tree = tree;
        }
}

/* Whole ray trees, for CPU devices: a work-item takes camera rays as
 * trace_persistent does (a packet of four with KDRT_PACKETS) and then traces
 * every bounce they spawn itself, depth first, as the C++ renderer recurses.
 * No ray queues, no launch per bounce level, and a pixel's rays all stay
 * with one work-item, which sums them in its own memory (the same
 * fixed-point sums, so the same image) and hands each pixel's sum to
 * to_pixel once: with one sample per pixel that is the pixel. A GPU keeps
 * the queues: its work-items run side by side, and ray trees of different
 * depths would leave most of them idle. counters[0] gets the bounce rays
 * traced, counters[2] the shadow rays. */
__kernel void trace_trees(KDRT_SCENE_PARAMS, KDRT_QUEUE_PARAMS) {
    const Scene scene = make_scene(KDRT_SCENE_ARGS, true);
    __local uint batch_base;
    KDRT_LAUNCH_COUNTERS;
    uint shadow_rays = 0, bounces = 0;
    for (;;) {
        if (get_local_id(0) == 0) batch_base = atomic_add(&counters[1], (uint)get_local_size(0) * KDRT_RAYS_PER_ITEM);
        barrier(CLK_LOCAL_MEM_FENCE);
        const uint base = batch_base;
        barrier(CLK_LOCAL_MEM_FENCE);
        if (base >= in_count) break;
        const uint i = base + (uint)get_local_id(0) * KDRT_RAYS_PER_ITEM;
        if (i >= in_count) continue;
        Spawned spawned[KDRT_RAYS_PER_ITEM];
        for (uint k = 0; k < KDRT_RAYS_PER_ITEM; ++k) spawned[k].mask = 0u;
        real3 colour[KDRT_RAYS_PER_ITEM];
        uint pixel[KDRT_RAYS_PER_ITEM];
        /* the camera rays (depth 1) */
        const uint n = shade_input(&scene, i, spawned, colour, pixel, &shadow_rays, KDRT_QUEUE_ARGS);
        ulong3 sum[KDRT_RAYS_PER_ITEM]; /* unsigned: wrapping adds, as add_fixed's */
        for (uint k = 0; k < n; ++k) sum[k] = as_ulong3(fixed_colour(colour[k]));
        PendingRay stack[KDRT_TREE_STACK];
        uint top = 0u;
        for (uint k = KDRT_RAYS_PER_ITEM; k-- > 0u;) push_spawned(stack, &top, &spawned[k], 2u, k);
        while (top > 0u) {
            const PendingRay p = stack[--top];
            Spawned sp;
            sp.mask = 0u;
            const real3 c = shade_ray(&scene, &p.ray, p.depth, &sp, ids, hit_t, 0u, &shadow_rays);
            sum[p.tree] += as_ulong3(fixed_colour(c));
            ++bounces;
            push_spawned(stack, &top, &sp, p.depth + 1u, p.tree);
        }
        for (uint k = 0; k < n; ++k) to_pixel(accum, rgb, rgb_out, pixel[k], as_long3(sum[k]), false);
    }
    if (bounces) atomic_add(&counters[0], bounces);
    if (shadow_rays) atomic_add(&counters[2], shadow_rays);
}
#endif

/* The accumulator's fixed-point sums (atomic_add_fixed) as the image's
 * floats (resolved_value), on the device: the host then reads half the
 * bytes and converts nothing. Each sum read is set to zero,
 * so the next frame starts from a clear accumulator without a fill: its
 * lines are in the cache here, where PoCL fills a buffer on one core. */
__kernel void resolve_image(__global uint* accum, __global float* rgb, ulong values) {
    const size_t i = get_global_id(0);
    if (i >= values) return;
    const long sum = (long)(((ulong)accum[2 * i + 1] << 32) | (ulong)accum[2 * i]);
    rgb[i] = resolved_value(sum);
    accum[2 * i] = 0u;
    accum[2 * i + 1] = 0u;
}

/* Size and field offsets of every shared structure as this compiler lays
 * them out, for the host to compare with its own. */
__kernel void report_layout(__global uint* out) {
    uint i = 0;
#define KDRT_REPORT(T, field) out[i++] = (uint)sizeof(T); out[i++] = (uint)(size_t)&(((T*)0)->field)
    KDRT_REPORT(KdNode, word1);
    KDRT_REPORT(KdLeafRopes, box_min);
    KDRT_REPORT(GpuSphere, material);
    KDRT_REPORT(GpuTriangle, zero);
    KDRT_REPORT(GpuMaterial, ior);
    KDRT_REPORT(GpuLight, color);
    KDRT_REPORT(GpuRay, pixel);
    KDRT_REPORT(GpuCamera, up);
    KDRT_REPORT(GpuSceneInfo, box_max);
    KDRT_REPORT(QueryRay, t_max);
    KDRT_REPORT(QueryHit, kind);
    KDRT_REPORT(GpuPackedLeaf, sphere_count);
    KDRT_REPORT(GpuLeafBlock, lanes);
    KDRT_REPORT(GpuBvhNode, count);
    KDRT_REPORT(GpuBvhSlot, count);
#ifdef KDRT_DOUBLE
    KDRT_REPORT(GpuSphereD, material);
    KDRT_REPORT(GpuTriangleD, v2);
    KDRT_REPORT(GpuRayD, weight);
    KDRT_REPORT(GpuCameraD, up);
    KDRT_REPORT(GpuLightD, color);
    KDRT_REPORT(GpuLeafBlockD, lanes);
#endif
#undef KDRT_REPORT
}
