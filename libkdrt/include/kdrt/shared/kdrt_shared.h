/* kdrt_shared.h: every structure that crosses the host/device boundary, defined
 * once. Included by C++ (libkdrt) and by OpenCL C (cl/). Rules: fixed-width
 * types only, no float3 / bool / size_t / bitfields, padding written out, and
 * the sizes checked on both sides (static_assert here, a device test that asks
 * the kernel for sizeof/offsetof).
 *
 * Float triples: a CPU's OpenCL compiler (PoCL) may load a float[3] as a
 * 4-lane vector and compute on all four lanes. So no triple is followed by an
 * integer: a small integer's bits are a denormal float, and each operation on
 * one costs an Intel core a microcode assist of a hundred-odd cycles (it made
 * PoCL's shading a fifth slower there). A triple is followed by another
 * triple, by an ordinary float, by a zero or by the end of the record.
 */
#ifndef KDRT_SHARED_H
#define KDRT_SHARED_H

#if defined(__OPENCL_VERSION__) || defined(__OPENCL_C_VERSION__)
#define KDRT_OPENCL_C 1
#endif

/* C++ sees every type below in namespace kdrt; OpenCL C has no namespaces. */
#if !defined(KDRT_OPENCL_C) && defined(__cplusplus)
#include <stdint.h>
namespace kdrt {
#endif

#ifdef KDRT_OPENCL_C
typedef uint kdrt_u32;
typedef int kdrt_i32;
typedef float kdrt_f32;
#else
#include <stdint.h>
typedef uint32_t kdrt_u32;
typedef int32_t kdrt_i32;
typedef float kdrt_f32;
#endif

/* ---- kd-tree layout -------------------------------------------------------
 * Nodes are 8 bytes in the style of pbrt's KdAccelNode, stored depth-first:
 * an inner node's "below" child (the side with smaller coordinates) is the
 * next node in the array, its "above" child is at `above_child`.
 *
 *   word0  inner: split position (float bits)   leaf: index of its first object
 *   word1  bits 0..1: split axis 0,1,2, or 3 for a leaf
 *          bits 2..31 inner: index of the above child; leaf: object count
 *
 * A leaf's objects are leaf_objects[word0 .. word0 + count), each an object id
 * (no separate leaf record: the traversal's leaf visit loads nothing but the
 * list) (spheres first, then triangles, as in FORMAT.md); an object is
 * stored once however many leaves refer to it.
 *
 * Ropes (Havran's neighbour links, pushed down after Popov et al. 2007): one
 * entry per node, indexed by node id (inner nodes' entries unused), for each
 * leaf six node indices, one per face (-x,+x,-y,+y,-z,+z), naming the
 * deepest node whose cell still covers the whole face, or KDRT_ROPE_NONE at
 * the scene boundary; with the leaf's box, which the rope traversal needs to
 * find its exit face.
 */
#define KDRT_LEAF_FLAG 3u
#define KDRT_ROPE_NONE 0xFFFFFFFFu
#define KDRT_MAX_NODE_INDEX 0x3FFFFFFFu
/* Deepest kd-tree the builders make and the loaders accept: it bounds the
 * fixed-size stacks of the stack traversal on the CPU and the device. */
#define KDRT_MAX_TREE_DEPTH 64
/* Entries of the short-stack traversal's ring buffer (Horn et al. 2007): when
 * it overflows, the oldest entry is dropped and recovered by a kd-restart. */
#ifndef KDRT_SHORT_STACK_SIZE
#define KDRT_SHORT_STACK_SIZE 4
#endif
/* Longest ray chain (camera ray = 1) a render accepts, from a scene file or an
 * option: it bounds the recursion of the C++ reference and the number of ray
 * queues on a device. */
#define KDRT_MAX_RAY_DEPTH 64
/* Per-ray cache of tested object ids (mailboxing) in the C++ and OpenCL
 * traversals: a power of two; KDRT_MAILBOX_EMPTY is never an object id. */
#define KDRT_MAILBOX_SIZE 16u
#define KDRT_MAILBOX_EMPTY 0xFFFFFFFFu

typedef struct KdNode {
    kdrt_u32 word0;
    kdrt_u32 word1;
} KdNode;

typedef struct KdLeafRopes {
    kdrt_u32 rope[6];   /* -x, +x, -y, +y, -z, +z */
    kdrt_f32 box_min[3];
    kdrt_f32 box_max[3];
} KdLeafRopes;

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
    kdrt_f32 zero;    /* 0: the fourth lane of v2 (see "float triples" above) */
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

/* ---- ray queries (kdrt/ray_query.h) ---------------------------------------
 * The application's rays and the hits returned for them, in world space, the
 * same bytes in host memory and in an application's cl_mem buffers. A ray
 * hits on (max(t_min, 0), t_max]: never behind its origin; direction need not
 * be normalised (t is in units of it). A miss has object == KDRT_NO_HIT and
 * the other fields unspecified. */
#define KDRT_NO_HIT 0xFFFFFFFFu
#define KDRT_KIND_NONE 0u
#define KDRT_KIND_SPHERE 1u
#define KDRT_KIND_TRIANGLE 2u

typedef struct QueryRay {
    kdrt_f32 origin[3];
    kdrt_f32 t_min;
    kdrt_f32 direction[3];
    kdrt_f32 t_max;
} QueryRay;

typedef struct QueryHit {
    kdrt_f32 t;
    kdrt_u32 object;   /* the scene's object id (Scene::add_* / FORMAT.md), or KDRT_NO_HIT */
    kdrt_u32 kind;     /* KDRT_KIND_SPHERE or KDRT_KIND_TRIANGLE */
    kdrt_f32 u, v;     /* triangle: barycentrics of v1 and v2; sphere: 0 */
    kdrt_f32 normal[3]; /* geometric normal, unit length, as wound (triangles) or outward (spheres) */
} QueryHit;

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

/* The order of a frame's camera rays (RenderOptions::ray_order): rows and
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

/* ---- double-precision twins (--precision double; devices with fp64) -------
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

#ifndef KDRT_OPENCL_C
#ifdef __cplusplus
static_assert(sizeof(GpuSphereD) == 48, "GpuSphereD must be 48 bytes");
static_assert(sizeof(GpuTriangleD) == 80, "GpuTriangleD must be 80 bytes");
static_assert(sizeof(GpuRayD) == 80, "GpuRayD must be 80 bytes");
static_assert(sizeof(GpuCameraD) == 120, "GpuCameraD must be 120 bytes");
static_assert(sizeof(GpuLightD) == 48, "GpuLightD must be 48 bytes");
static_assert(sizeof(GpuLeafBlockD) == 320, "GpuLeafBlockD must be 320 bytes");
static_assert(sizeof(GpuLeafBlock) == 176, "GpuLeafBlock must be 176 bytes");
static_assert(sizeof(GpuPackedLeaf) == 16, "GpuPackedLeaf must be 16 bytes");
static_assert(sizeof(GpuRay) == 48, "GpuRay must be 48 bytes");
static_assert(sizeof(GpuCamera) == 64, "GpuCamera must be 64 bytes");
static_assert(sizeof(GpuSceneInfo) == 64, "GpuSceneInfo must be 64 bytes");
static_assert(sizeof(QueryRay) == 32, "QueryRay must be 32 bytes");
static_assert(sizeof(QueryHit) == 32, "QueryHit must be 32 bytes");
static_assert(sizeof(KdNode) == 8, "KdNode must be 8 bytes");
static_assert(sizeof(KdLeafRopes) == 48, "KdLeafRopes must be 48 bytes");
static_assert(sizeof(GpuSphere) == 32, "GpuSphere must be 32 bytes");
static_assert(sizeof(GpuTriangle) == 48, "GpuTriangle must be 48 bytes");
static_assert(sizeof(GpuMaterial) == 48, "GpuMaterial must be 48 bytes");
static_assert(sizeof(GpuLight) == 32, "GpuLight must be 32 bytes");
#endif
#endif

#if !defined(KDRT_OPENCL_C) && defined(__cplusplus)
}  /* namespace kdrt */
#endif

#endif /* KDRT_SHARED_H */
