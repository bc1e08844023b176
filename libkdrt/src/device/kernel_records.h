/* kernel_records.h: the records and constants that only libkdrt and its
 * kernels exchange (scene buffers, ray queues, camera, packed leaves, the
 * traversals' fixed sizes), defined once. Included by C++ (libkdrt, in
 * namespace kdrt::detail) and by OpenCL C (cl/), where it comes second in the
 * program source, after kdrt/layout.h, whose rules it follows: fixed-width
 * types, padding written out, no integer after a float triple, sizes checked
 * on both sides (static_assert here, the device test of sizeof/offsetof).
 */
#ifndef KDRT_KERNEL_RECORDS_H
#define KDRT_KERNEL_RECORDS_H

#include <kdrt/layout.h>

#if !defined(KDRT_OPENCL_C) && defined(__cplusplus)
namespace kdrt::detail {
#endif

/* Entries of the short-stack traversal's ring buffer (Horn et al. 2007): when
 * it overflows, the oldest entry is dropped and recovered by a kd-restart. */
#ifndef KDRT_SHORT_STACK_SIZE
#define KDRT_SHORT_STACK_SIZE 4
#endif
/* Per-ray cache of tested object ids (mailboxing) in the C++ and OpenCL
 * traversals: a power of two; KDRT_MAILBOX_EMPTY is never an object id. */
#define KDRT_MAILBOX_SIZE 16u
#define KDRT_MAILBOX_EMPTY 0xFFFFFFFFu

/* Packed leaves (the kernels on CPU devices; libkdrt/src/kdtree/leaf_blocks.h):
 * a small tree's leaves with their triangles in blocks of KDRT_LEAF_LANES,
 * the vertices stored by component with a lane per triangle, so that a
 * block is nine vector loads. GpuPackedLeaf is indexed by where a leaf's list
 * starts in leaf_objects (unused entries zero); its spheres are
 * leaf_spheres[first_sphere ..], its blocks leaf_blocks[first_block ..]. */
#define KDRT_LEAF_LANES 4
typedef struct GpuPackedLeaf {
    kdrt_u32 first_block;
    kdrt_u32 block_count;
    kdrt_u32 first_sphere;
    kdrt_u32 sphere_count;
} GpuPackedLeaf;

typedef struct GpuLeafBlock {
    kdrt_f32 v[3][3][KDRT_LEAF_LANES]; /* [vertex][axis][lane] */
    kdrt_i32 id[KDRT_LEAF_LANES];      /* the lanes' object ids; unused lanes repeat lane 0's */
    kdrt_u32 lanes;                    /* bit k: lane k holds a triangle */
    kdrt_u32 pad[3];
} GpuLeafBlock;

/* ---- the wide BVH (libkdrt/src/bvh/bvh.h) ----------------------------------
 * KDRT_TRAVERSAL's value for the BVH's stack traversal
 * (cl/traverse_bvh.cl); 0..4 are the Traversal enum's. GpuBvhNode has the
 * bytes of WideBvhNode (static_asserts in opencl/gpu_records.h), so the host
 * uploads the BVH's nodes to CPU devices as they are (GPUs: GpuBvhSlot below):
 * a node's KDRT_BVH_WIDTH child slots by component, box[0] the lower bounds
 * and box[1] the upper, box[s][axis][slot];
 * a slot is an inner child (count 0, child: its node), a leaf (count
 * KDRT_BVH_LEAF_FLAG | k, its objects leaf_objects[child .. child + k)) or
 * empty (count KDRT_BVH_LEAF_FLAG, the empty box, after the used slots). No
 * float triples: a row of KDRT_BVH_WIDTH floats is read whole (vload8). The
 * deepest node is at KDRT_BVH_MAX_DEPTH (the root at 0): it bounds the stacks. */
#define KDRT_TRAVERSAL_BVH 5
#define KDRT_BVH_WIDTH 8
#define KDRT_BVH_LEAF_FLAG 0x80000000u
/* In the packed copy of the nodes that renders and closest and any-hit queries on CPU devices walk
 * (pack_bvh_nodes in libkdrt/src/kdtree/leaf_blocks.h), a leaf slot of
 * triangles is (first block, KDRT_BVH_LEAF_FLAG | block count), and one with
 * spheres (its GpuPackedLeaf's index, KDRT_BVH_LEAF_FLAG | KDRT_BVH_LEAF_RECORD). */
#define KDRT_BVH_LEAF_RECORD 0x40000000u
#define KDRT_BVH_MAX_DEPTH 63
/* The traversal's stack entries (cl/traverse_bvh.cl). CPU devices keep the
 * C++ twin's: every hit child of a node, sorted, so the deepest node's
 * KDRT_BVH_MAX_DEPTH ancestors leave at most WIDTH - 1 each and it pushes
 * WIDTH. GPUs keep one entry a node on the path: the node and its hit slots
 * still to visit. */
#define KDRT_BVH_SORTED_STACK_SIZE (KDRT_BVH_MAX_DEPTH * (KDRT_BVH_WIDTH - 1) + KDRT_BVH_WIDTH)
#define KDRT_BVH_SLOT_STACK_SIZE (KDRT_BVH_MAX_DEPTH + 1)
typedef struct GpuBvhNode {
    kdrt_f32 box[2][3][KDRT_BVH_WIDTH];
    kdrt_u32 child[KDRT_BVH_WIDTH];
    kdrt_u32 count[KDRT_BVH_WIDTH];
} GpuBvhNode;
/* A GPU gets the same nodes slot by slot instead (cl/bvh_node.cl): a node is
 * KDRT_BVH_WIDTH of these, the same 256 bytes, so that a slot's box and
 * reference are two 16-byte loads where the rows would take seven scattered
 * ones. Laid out by the host at upload (cl_scene_buffers.cpp). GPUs only:
 * the float triples' rule (kdrt/layout.h) is for CPU devices. */
typedef struct GpuBvhSlot {
    kdrt_f32 lo[3];
    kdrt_u32 child;
    kdrt_f32 hi[3];
    kdrt_u32 count;
} GpuBvhSlot;

/* ---- geometry in the renderer's working frame ------------------------------ */
typedef struct GpuSphere {
    kdrt_f32 center[3];
    kdrt_f32 radius;
    kdrt_u32 material;
    kdrt_u32 pad[3];
} GpuSphere;

#define KDRT_NO_NORMALS 0xFFFFFFFFu

typedef struct GpuTriangle {
    kdrt_u32 material;
    kdrt_u32 normals; /* index of this triangle's 3 shading normals in the normal array, or KDRT_NO_NORMALS */
    kdrt_f32 v0[3];
    kdrt_f32 v1[3];
    kdrt_f32 v2[3];
    kdrt_f32 zero;    /* 0: the fourth lane of v2 (see "float triples" in kdrt/layout.h) */
} GpuTriangle;

typedef struct GpuMaterial {
    kdrt_f32 color[3];
    kdrt_f32 diffuse;
    kdrt_f32 specular;
    kdrt_f32 shininess;
    kdrt_f32 reflect;
    kdrt_f32 transmit;
    kdrt_f32 ior;
    kdrt_f32 pad[3];
} GpuMaterial;

typedef struct GpuLight {
    kdrt_f32 position[3];
    kdrt_f32 pad0;
    kdrt_f32 color[3];
    kdrt_f32 pad1;
} GpuLight;

/* ---- the wavefront renderer's ray queues --------------------------------- */
/* A ray waiting to be traced: the pixel it contributes to and with what weight. */
typedef struct GpuRay {
    kdrt_f32 org[3];
    kdrt_f32 dir[3];
    kdrt_f32 weight[3];
    kdrt_f32 zero;     /* 0: the fourth lane of weight */
    kdrt_i32 ignore;   /* object the ray leaves, or -1 */
    kdrt_u32 pixel;
} GpuRay;

/* The order of a frame's camera rays (OpenClExecution::ray_order): rows and
 * KDRT_PIXEL_TILE x KDRT_PIXEL_TILE tiles (narrower at the right and bottom
 * edges) a GPU's frame kernel computes from a ray's index; otherwise a table
 * of pixels the host uploads (a Morton curve; every order on CPU devices). */
#define KDRT_PIXEL_ORDER_ROWS 0u
#define KDRT_PIXEL_ORDER_TILES 1u
#define KDRT_PIXEL_ORDER_TABLE 2u
#define KDRT_PIXEL_TILE 8u

/* The camera of FORMAT.md, as the kernels need it (frame computed on the host). */
typedef struct GpuCamera {
    kdrt_u32 width;
    kdrt_u32 height;
    kdrt_f32 tan_half_fov;
    kdrt_f32 aspect;
    kdrt_f32 position[3];
    kdrt_f32 forward[3];
    kdrt_f32 right[3];
    kdrt_f32 up[3];
} GpuCamera;

/* Scene-wide constants. */
typedef struct GpuSceneInfo {
    kdrt_u32 sphere_count;
    kdrt_u32 triangle_count;
    kdrt_u32 light_count;
    kdrt_u32 leaf_count;
    kdrt_f32 background[3];
    kdrt_f32 ambient[3];
    kdrt_f32 box_min[3];
    kdrt_f32 box_max[3];
} GpuSceneInfo;

/* ---- double-precision twins (precision double; devices with fp64) ---------
 * The same fields in double; only compiled into kernels built with
 * KDRT_DOUBLE, where the device has cl_khr_fp64. */
#if !defined(KDRT_OPENCL_C) || defined(KDRT_DOUBLE)
typedef double kdrt_f64;

typedef struct GpuSphereD {
    kdrt_f64 center[3];
    kdrt_f64 radius;
    kdrt_u32 material;
    kdrt_u32 pad[3];
} GpuSphereD;

typedef struct GpuTriangleD {
    kdrt_u32 material;
    kdrt_u32 normals;
    kdrt_f64 v0[3];
    kdrt_f64 v1[3];
    kdrt_f64 v2[3];
} GpuTriangleD;

typedef struct GpuRayD {
    kdrt_i32 ignore;
    kdrt_u32 pixel;
    kdrt_f64 org[3];
    kdrt_f64 dir[3];
    kdrt_f64 weight[3];
} GpuRayD;

typedef struct GpuLeafBlockD {
    kdrt_f64 v[3][3][KDRT_LEAF_LANES];
    kdrt_i32 id[KDRT_LEAF_LANES];
    kdrt_u32 lanes;
    kdrt_u32 pad[3];
} GpuLeafBlockD;

typedef struct GpuLightD {
    kdrt_f64 position[3];
    kdrt_f64 color[3];
} GpuLightD;

typedef struct GpuCameraD {
    kdrt_u32 width;
    kdrt_u32 height;
    kdrt_f64 tan_half_fov;
    kdrt_f64 aspect;
    kdrt_f64 position[3];
    kdrt_f64 forward[3];
    kdrt_f64 right[3];
    kdrt_f64 up[3];
} GpuCameraD;
#endif

#if !defined(KDRT_OPENCL_C) && defined(__cplusplus)
static_assert(sizeof(GpuSphereD) == 48, "GpuSphereD must be 48 bytes");
static_assert(sizeof(GpuTriangleD) == 80, "GpuTriangleD must be 80 bytes");
static_assert(sizeof(GpuRayD) == 80, "GpuRayD must be 80 bytes");
static_assert(sizeof(GpuCameraD) == 120, "GpuCameraD must be 120 bytes");
static_assert(sizeof(GpuLightD) == 48, "GpuLightD must be 48 bytes");
static_assert(sizeof(GpuLeafBlockD) == 320, "GpuLeafBlockD must be 320 bytes");
static_assert(sizeof(GpuLeafBlock) == 176, "GpuLeafBlock must be 176 bytes");
static_assert(sizeof(GpuPackedLeaf) == 16, "GpuPackedLeaf must be 16 bytes");
static_assert(sizeof(GpuBvhSlot) == 32 && KDRT_BVH_WIDTH * sizeof(GpuBvhSlot) == sizeof(GpuBvhNode),
              "a node's GpuBvhSlots must have the bytes of one GpuBvhNode");
static_assert(sizeof(GpuBvhNode) == 256, "GpuBvhNode must be 256 bytes");
static_assert(sizeof(GpuRay) == 48, "GpuRay must be 48 bytes");
static_assert(sizeof(GpuCamera) == 64, "GpuCamera must be 64 bytes");
static_assert(sizeof(GpuSceneInfo) == 64, "GpuSceneInfo must be 64 bytes");
static_assert(sizeof(GpuSphere) == 32, "GpuSphere must be 32 bytes");
static_assert(sizeof(GpuTriangle) == 48, "GpuTriangle must be 48 bytes");
static_assert(sizeof(GpuMaterial) == 48, "GpuMaterial must be 48 bytes");
static_assert(sizeof(GpuLight) == 32, "GpuLight must be 32 bytes");
}  /* namespace kdrt::detail */
#endif

#endif /* KDRT_KERNEL_RECORDS_H */
