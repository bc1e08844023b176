/* common.cl: types and small helpers shared by every kernel file.
 *
 * Specialisation (-D options chosen by the host from the scene's features):
 *   KDRT_HAS_SPHERES, KDRT_HAS_TRIANGLES, KDRT_HAS_NORMALS  geometry present
 *   KDRT_HAS_LIGHTS       trace shadow rays
 *   KDRT_HAS_REFLECTION   mirror rays;  KDRT_HAS_REFRACTION  refracted rays
 *   KDRT_MAX_DEPTH        longest ray chain (1: no bounce code at all)
 *   KDRT_TRAVERSAL        0 none, 1 restart, 2 ropes, 3 stack, 4 short-stack (the kd-tree's),
 *                         KDRT_TRAVERSAL_BVH (5) the wide BVH's stack (traverse_bvh.cl)
 *   KDRT_SHORT_STACK_SIZE entries of the short stack (default in kernel_records.h)
 *   KDRT_DOUBLE           all geometry and arithmetic in double (needs fp64)
 *   KDRT_MAILBOX          the kd-tree has objects in several leaves: test each once per ray
 *   KDRT_CPU_DEVICE       a CPU device (PoCL): a leaf's triangles four at a time in vector
 *                         lanes (visit_objects.cl) and prefetches the compiler does not drop
 *   KDRT_PACKETS          4: a work-item traces four rays as a packet (CPU devices, the
 *                         kd-tree's stack traversal or the BVH; traverse_packet.cl,
 *                         traverse_bvh_packet.cl)
 *   KDRT_PACKED_LEAVES    a small tree's or BVH's leaves come as blocks of four triangles too
 *                         (GpuPackedLeaf; visit_packed_leaf in visit_objects.cl): CPU devices,
 *                         watertight test, scenes with triangles
 */
#if defined(KDRT_PACKED_LEAVES) && \
    (!defined(KDRT_CPU_DEVICE) || !defined(KDRT_HAS_TRIANGLES) || defined(KDRT_MOLLER_TRUMBORE))
#error "KDRT_PACKED_LEAVES needs KDRT_CPU_DEVICE, KDRT_HAS_TRIANGLES and the watertight test"
#endif
#if defined(KDRT_HAS_FP64) || defined(KDRT_DOUBLE)
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#endif
#pragma OPENCL FP_CONTRACT OFF /* a*b - c*d must round the same way for both triangles of an edge */

#ifndef KDRT_MAX_DEPTH
#define KDRT_MAX_DEPTH 1
#endif
#ifndef KDRT_TRAVERSAL
#define KDRT_TRAVERSAL 3
#endif
#define KDRT_NONE_ID (-1)

/* The working precision: geometry, rays and their arithmetic. Colours are
 * accumulated in fixed point either way (atomic_add_fixed). */
#ifdef KDRT_DOUBLE
typedef double real;
typedef double3 real3;
typedef GpuSphereD SphereRec;
typedef GpuTriangleD TriangleRec;
typedef GpuRayD RayRec;
typedef GpuCameraD CameraRec;
typedef GpuLightD LightRec;
typedef GpuLeafBlockD LeafBlockRec;
#define KDRT_SLACK_EPS 1e-13           /* traversal termination slack, relative */
#define KDRT_OFFSET_REL 7.105427357601002e-15  /* 2^-47: ray origin offset, relative to the object */
#else
typedef float real;
typedef float3 real3;
typedef GpuSphere SphereRec;
typedef GpuTriangle TriangleRec;
typedef GpuRay RayRec;
typedef GpuCamera CameraRec;
typedef GpuLight LightRec;
typedef GpuLeafBlock LeafBlockRec;
#define KDRT_SLACK_EPS 1e-5f
#define KDRT_OFFSET_REL 3.814697265625e-06f    /* 2^-18 */
#endif
#define R(x) ((real)(x))
#define REAL_INF ((real)INFINITY)

/* Inlined wherever it is called (GPU compilers inline everything anyway):
 * the hot functions that PoCL 3.1's inliner would keep as calls. The
 * traversal, so that closest_hit and occluded each get a copy specialised on
 * any_hit; helpers whose arrays would otherwise go through memory. */
#define KDRT_INLINE inline __attribute__((always_inline))

/* A cache line wanted soon. PoCL compiles OpenCL's prefetch() to nothing, so
 * a CPU device gets Clang's builtin (a prefetch instruction); a GPU keeps
 * prefetch(), and hides latency with its other work-items anyway. */
#if defined(KDRT_CPU_DEVICE) && defined(__has_builtin)
#if __has_builtin(__builtin_prefetch)
#define KDRT_PREFETCH(p) __builtin_prefetch((p), 0, 3)
#endif
#endif
#ifndef KDRT_PREFETCH
#define KDRT_PREFETCH(p) prefetch((__global const uchar*)(p), 1)
#endif
/* A cache line about to be written: only CPU devices ask for it (a GPU's
 * stores do not wait for their lines). */
#if defined(KDRT_CPU_DEVICE) && defined(__has_builtin)
#if __has_builtin(__builtin_prefetch)
#define KDRT_PREFETCH_WRITE(p) __builtin_prefetch((p), 1, 3)
#endif
#endif
#ifndef KDRT_PREFETCH_WRITE
#define KDRT_PREFETCH_WRITE(p) ((void)0)
#endif

/* Every cache line that [p, p + bytes) touches, wanted soon (the C++ devices'
 * prefetch_lines): a line per 64 bytes from p, and the last byte's. Forced
 * inline, so that its callers' constant sizes unroll the loop. */
KDRT_INLINE void prefetch_lines(__global const uchar* p, uint bytes) {
    for (uint at = 0u; at < bytes; at += 64u) KDRT_PREFETCH(p + at);
    KDRT_PREFETCH(p + bytes - 1u);
}

/* The index of the lowest set bit of a non-zero lane mask (ctz is OpenCL 2.0). */
inline uint lowest_lane(uint l) { return 31u - clz(l & (0u - l)); }

#ifdef KDRT_CPU_DEVICE
/* Four lanes of the working precision, for the CPU code's vector tests
 * (visit_objects.cl, traverse_packet.cl), and their comparisons' masks. */
#ifdef KDRT_DOUBLE
typedef double4 real4;
typedef long4 mask4;
typedef long3 mask3;
#define convert_real4 convert_double4
#else
typedef float4 real4;
typedef int4 mask4;
typedef int3 mask3;
#define convert_real4 convert_float4
#endif

/* Bit i set where lane i of a comparison is true (OpenCL: all bits set; the
 * x86 form reads only the sign bits, so m must be such a mask). On x86 that
 * is one movmsk instruction, which LLVM does not find in the portable form:
 * its masks, shuffles and ors were a fifth of watertight_lanes' samples on
 * insane. */
#if defined(__clang__) && defined(__has_builtin)
#if __has_builtin(__builtin_ia32_movmskps) && defined(__SSE__)
#define KDRT_MOVMSKPS
#endif
#if __has_builtin(__builtin_ia32_movmskpd256) && defined(__AVX__)
#define KDRT_MOVMSKPD256
#endif
#endif
#if defined(KDRT_MOVMSKPS) && !defined(KDRT_DOUBLE)
inline uint lane_bits(mask4 m) { return (uint)__builtin_ia32_movmskps(as_float4(m)); }
#elif defined(KDRT_MOVMSKPD256) && defined(KDRT_DOUBLE)
inline uint lane_bits(mask4 m) { return (uint)__builtin_ia32_movmskpd256(as_double4(m)); }
#else
inline uint lane_bits(mask4 m) {
    const mask4 b = m & (mask4)(1, 2, 4, 8);
    return (uint)(b.s0 | b.s1 | b.s2 | b.s3);
}
#endif
/* lane_bits of a 32-bit integer comparison, in either precision (a true
 * lane's -1 stays -1 when widened). */
#ifdef KDRT_DOUBLE
inline uint int_lane_bits(int4 m) { return lane_bits(convert_long4(m)); }
#else
inline uint int_lane_bits(int4 m) { return lane_bits(m); }
#endif
#endif

/* A float[3] or double[3] in any address space as a vector. */
#define load3(p) ((real3)((real)(p)[0], (real)(p)[1], (real)(p)[2]))
inline real get3(real3 v, int axis) { return axis == 0 ? v.x : (axis == 1 ? v.y : v.z); }

/* The geometric functions as the C++ twin computes them, operation for
 * operation (glm, and safe_length/safe_normalize in src/cpu/surface.h). The
 * built-ins may fuse multiply-adds or take reciprocal square roots whatever
 * FP_CONTRACT says (NVIDIA's do), and hit distances one ulp off the twin's
 * then changed which object was closest. Vectors beyond 2^60 are scaled by
 * 2^-64 first, exactly, so that their squares do not overflow. */
inline real dot3(real3 a, real3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline real3 cross3(real3 x, real3 y) {
    return (real3)(x.y * y.z - y.y * x.z, x.z * y.x - y.z * x.x, x.x * y.y - y.x * x.y);
}
inline bool beyond_2_60(real3 v) { return fmax(fabs(v.x), fmax(fabs(v.y), fabs(v.z))) > R(1.152921504606846976e18); }
inline real length3(real3 v) {
    if (!beyond_2_60(v)) return sqrt(dot3(v, v));
    v *= R(5.42101086242752217e-20);
    return R(18446744073709551616.0) * sqrt(dot3(v, v));
}
inline real3 normalize3(real3 v) {
    if (beyond_2_60(v)) v *= R(5.42101086242752217e-20);
    return v * (R(1) / sqrt(dot3(v, v)));
}

/* Colours are summed per pixel in 64-bit fixed point, units of 2^-32
 * (range +-2^31): integer addition is associative, so a pixel's sum does not
 * depend on the order its rays finish in (two rays of one pixel can finish
 * in the same launch) nor on which other pixels share its launches (regions,
 * tiles). Float addition through compare-and-swap did. The 64-bit add is two
 * 32-bit atomics (OpenCL 1.2 core): the low word, then the high word with the
 * carry; only the finished sum is read (by resolve_image, render.cl). */
#define KDRT_ACCUM_ONE 4294967296.0 /* 2^32 */

/* convert_long_sat_rte(v), bit for bit, without a branch: PoCL's rounds
 * through a software rint whose branches depend on the value. From 2^23
 * (double: 2^52) up a real is an integer already; below, adding and
 * subtracting that power of two rounds to the nearest even integer in the
 * default rounding mode (FP_CONTRACT is off, so the sum is rounded). */
inline long fixed_from_real(real v) {
#ifdef KDRT_DOUBLE
    const real big = 4503599627370496.0; /* 2^52 */
#else
    const real big = 8388608.0f; /* 2^23 */
#endif
    const real shift = copysign(big, v);
    return convert_long_sat(fabs(v) < big ? (v + shift) - shift : v);
}
inline void atomic_add_fixed(volatile __global uint* p, long value) {
    if (value == 0) return; /* black: nothing to add */
    const uint lo = (uint)value, hi = (uint)((ulong)value >> 32);
    const uint old = atomic_add(p, lo);
    const uint high = hi + ((uint)(old + lo) < old ? 1u : 0u); /* with the carry */
    if (high != 0u) atomic_add(p + 1, high); /* mostly 0: colours below 1 without a carry */
}

/* The scene as the kernels see it: buffer pointers plus constants. */
typedef struct Scene {
    __global const SphereRec* spheres;
    __global const TriangleRec* triangles;
    __global const real* normals;
    __global const GpuMaterial* materials;
    __global const LightRec* lights;
    __global const KdNode* nodes;
    __global const uint* leaf_objects;
    __global const KdLeafRopes* ropes;
    /* KDRT_TRAVERSAL_BVH: the BVH's nodes, their leaves in leaf_objects; where
     * `packed`, their packed copy, whose leaf slots refer to leaf_blocks
     * (KDRT_BVH_LEAF_RECORD in kernel_records.h) */
    __global const GpuBvhNode* bvh_nodes;
    /* with KDRT_PACKED_LEAVES (visit_packed_leaf): a kd-tree's by where a
     * leaf's list starts; a BVH's leaves with spheres, by their slots' index */
    __global const GpuPackedLeaf* packed_leaves;
    __global const LeafBlockRec* leaf_blocks;
    __global const uint* leaf_spheres;
    uint sphere_count, triangle_count, light_count, leaf_count;
    bool packed; /* the leaves are tested through packed_leaves (renders, closest-hit and any-hit queries) */
    real3 box_min, box_max;
    real3 background, ambient;
} Scene;

/* A ray with its precomputed watertight-test shear and reciprocal direction
 * (the twin of libkdrt/src/cpu/ray.h). */
typedef struct Ray {
    real3 org, dir, inv_dir;
    int kx, ky, kz;
    real sx, sy, sz;
    int ignore;
    real org_max; /* largest |org| component: the termination slack scales with it */
} Ray;

/* The watertight test's other two axes for the dominant one, kz: (kz + 1) % 3
 * and (kz + 2) % 3 without a remainder, swapped where dir[kz] < 0 (flip) to
 * keep the winding. */
inline void shear_axes(int kz, bool flip, int* kx, int* ky) {
    const int next = kz == 2 ? 0 : kz + 1, prev = kz == 0 ? 2 : kz - 1;
    *kx = flip ? prev : next;
    *ky = flip ? next : prev;
}

inline Ray make_ray(real3 org, real3 dir, int ignore) {
    Ray r;
    r.org = org;
    r.dir = dir;
    r.inv_dir = R(1) / dir;
    r.ignore = ignore;
    real3 ad = fabs(dir);
    r.kz = (ad.x > ad.y) ? (ad.x > ad.z ? 0 : 2) : (ad.y > ad.z ? 1 : 2);
    shear_axes(r.kz, get3(dir, r.kz) < R(0), &r.kx, &r.ky);
    r.sx = get3(dir, r.kx) / get3(dir, r.kz);
    r.sy = get3(dir, r.ky) / get3(dir, r.kz);
    r.sz = R(1) / get3(dir, r.kz);
    const real3 ao = fabs(org);
    r.org_max = fmax(fmax(ao.x, ao.y), ao.z);
    return r;
}

#ifdef KDRT_CPU_DEVICE
/* make_ray for four rays at once, lane k of the vectors being ray k's org
 * and dir (x, y, z), into r[0..3]: the same IEEE operations lane by lane, so
 * the same rays, with the four rays' divisions in flight together. */
inline void make_rays4(const real4* org, const real4* dir, int ignore, Ray* r) {
    const real4 ax = fabs(dir[0]), ay = fabs(dir[1]), az = fabs(dir[2]);
    /* kz as make_ray picks it: x where pick_x, y where pick_y, else z */
    const mask4 x_over_y = ax > ay;
    const mask4 pick_x = x_over_y & (ax > az), pick_y = ~x_over_y & (ay > az);
    /* dir along kz, (kz + 1) % 3 and (kz + 2) % 3 */
    const real4 d_kz = select(select(dir[2], dir[1], pick_y), dir[0], pick_x);
    const real4 d_next = select(select(dir[0], dir[2], pick_y), dir[1], pick_x);
    const real4 d_prev = select(select(dir[1], dir[0], pick_y), dir[2], pick_x);
    const mask4 flip = d_kz < R(0); /* kx and ky swapped */
    real o[3][4], d[3][4], inv[3][4], shear[3][4], org_max[4];
    for (int a = 0; a < 3; ++a) {
        vstore4(org[a], 0, o[a]);
        vstore4(dir[a], 0, d[a]);
        vstore4(R(1) / dir[a], 0, inv[a]);
    }
    vstore4(select(d_next, d_prev, flip) / d_kz, 0, shear[0]);
    vstore4(select(d_prev, d_next, flip) / d_kz, 0, shear[1]);
    vstore4(R(1) / d_kz, 0, shear[2]);
    vstore4(fmax(fmax(fabs(org[0]), fabs(org[1])), fabs(org[2])), 0, org_max);
    const uint px = lane_bits(pick_x), py = lane_bits(pick_y), neg = lane_bits(flip);
    for (uint k = 0; k < 4u; ++k) {
        r[k].org = (real3)(o[0][k], o[1][k], o[2][k]);
        r[k].dir = (real3)(d[0][k], d[1][k], d[2][k]);
        r[k].inv_dir = (real3)(inv[0][k], inv[1][k], inv[2][k]);
        r[k].ignore = ignore;
        r[k].kz = ((px >> k) & 1u) != 0u ? 0 : ((py >> k) & 1u) != 0u ? 1 : 2;
        shear_axes(r[k].kz, ((neg >> k) & 1u) != 0u, &r[k].kx, &r[k].ky);
        r[k].sx = shear[0][k];
        r[k].sy = shear[1][k];
        r[k].sz = shear[2][k];
        r[k].org_max = org_max[k];
    }
}
#endif

typedef struct Hit {
    real t;
    int id;
    real b1, b2;
} Hit;

inline Hit no_hit(void) {
    Hit h;
    h.t = REAL_INF;
    h.id = KDRT_NONE_ID;
    h.b1 = h.b2 = R(0);
    return h;
}

/* The one ordering every traversal uses: nearer first, then the lower id. */
inline bool closer_than(real t, int id, Hit best) { return t < best.t || (t == best.t && id < best.id); }

/* Mailbox: the objects this ray was already tested against, so that an object
 * in several leaves is tested once; a small direct-mapped cache of ids, the
 * twin of libkdrt/src/cpu/mailbox.h (a collision only repeats a test). */
#ifdef KDRT_MAILBOX /* set by the host when the tree has an object in two leaves */
typedef struct Mailbox {
    uint ids[KDRT_MAILBOX_SIZE];
} Mailbox;

inline void clear_mailbox(Mailbox* m) {
    for (uint i = 0; i < KDRT_MAILBOX_SIZE; ++i) m->ids[i] = KDRT_MAILBOX_EMPTY;
}

inline bool mailbox_seen(Mailbox* m, uint id) {
    const uint slot = id & (KDRT_MAILBOX_SIZE - 1u);
    if (m->ids[slot] == id) return true;
    m->ids[slot] = id;
    return false;
}
#else /* NoMailbox */
typedef struct Mailbox {
    uint unused;
} Mailbox;

inline void clear_mailbox(Mailbox* m) { m->unused = 0u; }
inline bool mailbox_seen(Mailbox* m, uint id) { return false; }
#endif
