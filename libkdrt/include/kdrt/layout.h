/* kdrt/layout.h: the records an application passes to kdrt or reads back in
 * the kernels' own layout, defined once: the ray queries' rays and hits
 * (kdrt/ray_query.h, kdrt/opencl_interop.h) and the kd-tree's nodes and ropes
 * (kdrt/kd_tree.h, tree files). Included by C++, C99 and OpenCL C (kdrt's
 * kernels put it first in their program source). The kernels' private records
 * are in libkdrt/src/device/kernel_records.h, under the same rules.
 *
 * Rules: fixed-width types only, no float3 / bool / size_t / bitfields,
 * padding written out, and the sizes checked on both sides (static_assert
 * here, a device test that asks the kernel for sizeof/offsetof).
 *
 * Float triples: a CPU's OpenCL compiler (PoCL) may load a float[3] as a
 * 4-lane vector and compute on all four lanes. So no triple is followed by an
 * integer: a small integer's bits are a denormal float, and each operation on
 * one costs an Intel core a microcode assist of a hundred-odd cycles. A triple
 * is followed by another triple, by an ordinary float, by a zero or by the
 * end of the record.
 */
#ifndef KDRT_LAYOUT_H
#define KDRT_LAYOUT_H

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
/* Longest ray chain (camera ray = 1) a render accepts, from a scene file or an
 * option: it bounds the recursion of the C++ reference and the number of ray
 * queues on a device. */
#define KDRT_MAX_RAY_DEPTH 64

typedef struct KdNode {
    kdrt_u32 word0;
    kdrt_u32 word1;
} KdNode;

typedef struct KdLeafRopes {
    kdrt_u32 rope[6];   /* -x, +x, -y, +y, -z, +z */
    kdrt_f32 box_min[3];
    kdrt_f32 box_max[3];
} KdLeafRopes;

/* ---- ray queries (kdrt/ray_query.h) ---------------------------------------
 * The application's rays and the hits returned for them, in world space, the
 * same bytes in host memory and in an application's cl_mem buffers. A ray
 * hits on (max(t_min, 0), t_max]: never behind its origin; direction need not
 * be normalised (t is in units of it). A miss has t = +inf, object, geometry
 * and primitive KDRT_NO_HIT, kind KDRT_KIND_NONE and the other fields
 * unspecified. */
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

/* A hit names its object twice: by the scene's flat object id, and as the
 * geometry (the add_* call that added it, kdrt/scene.h) with the primitive
 * within that geometry, as Embree and Open3D do. */
typedef struct QueryHit {
    kdrt_f32 t;
    kdrt_f32 normal[3]; /* geometric normal, unit length, as wound (triangles) or outward (spheres) */
    kdrt_f32 u, v;      /* triangle: barycentrics of v1 and v2; sphere: 0 */
    kdrt_u32 object;    /* the scene's object id (Scene::add_* / FORMAT.md), or KDRT_NO_HIT */
    kdrt_u32 geometry;  /* the geometry id (Scene::geometry_count() before its add_* call), or KDRT_NO_HIT */
    kdrt_u32 primitive; /* the object's index within its geometry, or KDRT_NO_HIT */
    kdrt_u32 kind;      /* KDRT_KIND_SPHERE or KDRT_KIND_TRIANGLE */
} QueryHit;

/* The point of the scene's surface closest to a query point
 * (kdrt::closest_points): the same naming as QueryHit. No surface within
 * reach (an empty scene): distance +inf, ids KDRT_NO_HIT. */
typedef struct ClosestPoint {
    kdrt_f32 point[3];    /* the closest point, world space */
    kdrt_f32 distance;    /* from the query point */
    kdrt_f32 normal[3];   /* the primitive's geometric normal there, as in QueryHit */
    kdrt_f32 u, v;        /* triangle: barycentrics of v1 and v2 of the point; sphere: 0 */
    kdrt_u32 object;
    kdrt_u32 geometry;
    kdrt_u32 primitive;
} ClosestPoint;

#if !defined(KDRT_OPENCL_C) && defined(__cplusplus)
static_assert(sizeof(QueryRay) == 32, "QueryRay must be 32 bytes");
static_assert(sizeof(QueryHit) == 40, "QueryHit must be 40 bytes");
static_assert(sizeof(ClosestPoint) == 48, "ClosestPoint must be 48 bytes");
static_assert(sizeof(KdNode) == 8, "KdNode must be 8 bytes");
static_assert(sizeof(KdLeafRopes) == 48, "KdLeafRopes must be 48 bytes");
}  /* namespace kdrt */
#endif

#endif /* KDRT_LAYOUT_H */
