#include "opencl/cl_scene_buffers.h"

#include "kdtree/leaf_blocks.h"
#include "opencl/gpu_records.h"
#include "opencl/kernel_variant.h"

#include <kdrt/error.h>

#include <algorithm>
#include <cstring>

namespace kdrt::detail::ocl {

namespace {

// A read-only buffer of `count` records (one dummy when empty: OpenCL has no
// zero-sized buffers), checked against the device's limits, written in place
// by fill(T* records) through a mapping: records go straight into the
// device's memory, with no host vector in between. Adds its size to *bytes.
template <class T, class Fill>
cl::Buffer upload_records(const ClDeviceContext& dev, std::size_t count, const char* what, std::uint64_t* bytes,
                          Fill&& fill) {
    const std::size_t size = std::max<std::size_t>(1, count) * sizeof(T);
    check_allocation(dev.device(), size, what);
    cl::Buffer buffer(dev.context(), CL_MEM_READ_ONLY | CL_MEM_ALLOC_HOST_PTR, size);
    auto* records =
        static_cast<T*>(dev.queue().enqueueMapBuffer(buffer, CL_TRUE, CL_MAP_WRITE_INVALIDATE_REGION, 0, size));
    if (count == 0) std::memset(static_cast<void*>(records), 0, sizeof(T));
    else fill(records);
    dev.queue().enqueueUnmapMemObject(buffer, records);
    *bytes += size;
    return buffer;
}

template <class T>
cl::Buffer upload_array(const ClDeviceContext& dev, const std::vector<T>& data, const char* what,
                        std::uint64_t* bytes) {
    return upload_records<T>(dev, data.size(), what, bytes,
                             [&](T* out) { std::memcpy(static_cast<void*>(out), data.data(), data.size() * sizeof(T)); });
}

// A GPU's copy of the BVH nodes (GpuBvhSlot, kernel_records.h): each node's
// slots one after another, a slot's lower bounds and child, then its upper
// bounds and count.
void put_bvh_slots(const std::vector<WideBvhNode>& nodes, GpuBvhNode* out) {
    auto* bytes = reinterpret_cast<unsigned char*>(out);
    for (const WideBvhNode& n : nodes)
        for (int s = 0; s < kWideBvhWidth; ++s) {
            GpuBvhSlot slot{};
            for (int a = 0; a < 3; ++a) {
                slot.lo[a] = n.box[0][a][s];
                slot.hi[a] = n.box[1][a][s];
            }
            slot.child = n.child[s];
            slot.count = n.count[s];
            std::memcpy(bytes, &slot, sizeof slot);
            bytes += sizeof slot;
        }
}

}  // namespace

std::uint64_t ClSceneBuffers::upload_geometry(const ClDeviceContext& device, const PreparedScene& scene,
                                              AccelRef accel, Precision precision,
                                              const std::function<bool(double)>& progress) {
    uploaded_ = false;
    geometry_bytes_ = 0;
    precision_ = precision;
    if (accel.bvh) accel.kd = nullptr;  // the BVH is traced where there is one (as on the cpu device)
    if (precision == Precision::Double) upload_geometry_in<double>(device, scene, accel, progress);
    else upload_geometry_in<float>(device, scene, accel, progress);
    const std::uint64_t geometry = geometry_bytes_;
    const std::uint64_t shading = upload_shading(device, scene);
    if (id_map_() == nullptr) upload_id_map(device, {});
    device.queue().finish();
    uploaded_ = true;
    return geometry + shading;
}

std::uint64_t ClSceneBuffers::upload_shading(const ClDeviceContext& device, const PreparedScene& scene) {
    shading_bytes_ = 0;
    if (precision_ == Precision::Double) upload_shading_in<double>(device, scene);
    else upload_shading_in<float>(device, scene);
    return shading_bytes_;
}

template <class Real>
void ClSceneBuffers::upload_geometry_in(const ClDeviceContext& dev, const PreparedScene& scene, AccelRef accel,
                                        const std::function<bool(double)>& progress) {
    using Records = GpuRecords<Real>;
    const auto& g = scene.template geometry<Real>();
    static const KdTree empty_tree;
    static const WideBvh empty_bvh;
    const KdTree& kd = accel.kd ? *accel.kd : empty_tree;
    const WideBvh& bvh = accel.bvh ? *accel.bvh : empty_bvh;
    const std::vector<std::uint32_t>& leaf_objects = accel.bvh ? bvh.leaf_objects : kd.leaf_objects;
    // The finished fraction by bytes; the queue is idle between buffers (blocking maps).
    const double total = static_cast<double>(g.spheres.size() * sizeof(typename Records::Sphere) +
                                             g.triangles.size() * sizeof(typename Records::Triangle) +
                                             g.normals.size() * 3 * sizeof(Real) + kd.nodes.size() * sizeof(KdNode) +
                                             bvh.nodes.size() * sizeof(GpuBvhNode) +
                                             leaf_objects.size() * sizeof(std::uint32_t) +
                                             kd.ropes.size() * sizeof(KdLeafRopes)) +
                         1.0;
    auto report = [&] {
        if (progress && !progress(std::min(1.0, static_cast<double>(geometry_bytes_) / total)))
            throw Error(ErrorCode::Cancelled, "upload to the OpenCL device cancelled by the progress callback");
    };
    spheres_ = upload_records<typename Records::Sphere>(dev, g.spheres.size(), "the spheres", &geometry_bytes_,
                                                        [&](auto* out) {
                                                            for (const auto& s : g.spheres) {
                                                                typename Records::Sphere d{};
                                                                put3(d.center, s.center);
                                                                d.radius = s.radius;
                                                                d.material = s.material;
                                                                *out++ = d;
                                                            }
                                                        });
    triangles_ = upload_records<typename Records::Triangle>(dev, g.triangles.size(), "the triangles",
                                                            &geometry_bytes_, [&](auto* out) {
                                                                for (const auto& t : g.triangles) {
                                                                    typename Records::Triangle d{};
                                                                    put3(d.v0, t.v0);
                                                                    put3(d.v1, t.v1);
                                                                    put3(d.v2, t.v2);
                                                                    d.material = t.material;
                                                                    d.normals = t.normals == kNoNormal
                                                                                    ? KDRT_NO_NORMALS
                                                                                    : t.normals;
                                                                    *out++ = d;
                                                                }
                                                            });
    report();
    normals_ = upload_records<Real>(dev, 3 * g.normals.size(), "the shading normals", &geometry_bytes_, [&](Real* out) {
        for (const auto& n : g.normals) {
            put3(out, n);
            out += 3;
        }
    });
    report();
    nodes_ = upload_array(dev, kd.nodes, "the kd-tree nodes", &geometry_bytes_);
    ropes_ = upload_array(dev, kd.ropes, "the kd-tree ropes", &geometry_bytes_);
    // CPU devices take the nodes as they are (GpuBvhNode is WideBvhNode's
    // bytes, gpu_records.h); GPUs slot by slot (cl/bvh_node.cl).
    const bool slot_major = !cpu_kernels(dev.device());
    bvh_nodes_ = upload_records<GpuBvhNode>(dev, bvh.nodes.size(), "the BVH nodes", &geometry_bytes_,
                                            [&](GpuBvhNode* out) {
                                                if (slot_major) put_bvh_slots(bvh.nodes, out);
                                                else std::memcpy(static_cast<void*>(out), bvh.nodes.data(),
                                                                 bvh.nodes.size() * sizeof(GpuBvhNode));
                                            });
    leaf_objects_ = upload_array(dev, leaf_objects, accel.bvh ? "the BVH leaf lists" : "the kd-tree leaf lists",
                                 &geometry_bytes_);
    upload_packed_leaves<Real>(dev, scene, accel);
    report();

    info_ = GpuSceneInfo{};
    info_.sphere_count = static_cast<std::uint32_t>(g.spheres.size());
    info_.triangle_count = static_cast<std::uint32_t>(g.triangles.size());
    info_.leaf_count = static_cast<std::uint32_t>(kd.leaf_count());  // the ropes traversal's bound (kd-tree only)
    const Aabb& box = accel.bvh ? bvh.bounds : kd.bounds;
    put3(info_.box_min, box.empty() ? glm::dvec3(0.0) : box.lo);
    put3(info_.box_max, box.empty() ? glm::dvec3(0.0) : box.hi);
}

// The CPU devices' leaf test takes a leaf's triangles four at a time; packed
// (GpuLeafBlock), a block is nine vector loads instead of twelve vertices
// gathered into lanes. Made once per commit, as the cpu device packs: a
// BVH's leaves always, a kd-tree's up to kPackedLeafRefsMax references.
template <class Real>
void ClSceneBuffers::upload_packed_leaves(const ClDeviceContext& dev, const PreparedScene& scene, AccelRef accel) {
    using Block = typename GpuRecords<Real>::LeafBlock;
    const auto& g = scene.template geometry<Real>();
    const auto sphere_count = static_cast<std::uint32_t>(g.spheres.size());
    LeafBlocks plan;
    if (!g.triangles.empty() && cpu_kernels(dev.device())) {
        if (accel.bvh) {
            plan = plan_leaf_blocks(*accel.bvh, sphere_count, KDRT_LEAF_LANES);
        } else if (accel.kd) {
            plan = plan_leaf_blocks(*accel.kd, sphere_count, KDRT_LEAF_LANES, kPackedLeafRefsMax);
        }
    }
    leaves_packed_ = !plan.empty();
    // A kd-tree's leaf records by where each leaf's list starts; a BVH's
    // nodes copied with their leaf slots referring to the blocks, and the
    // records of its leaves with spheres only.
    std::vector<LeafBlocks::Leaf> records;
    std::vector<WideBvhNode> packed_nodes;
    if (leaves_packed_ && accel.bvh) {
        packed_nodes = pack_bvh_nodes(*accel.bvh, plan, records);
    } else if (leaves_packed_) {
        records.resize(plan.leaf_at.size(), LeafBlocks::Leaf{0, 0, 0, 0});
        for (std::size_t first = 0; first < plan.leaf_at.size(); ++first)
            if (plan.leaf_at[first] != LeafBlocks::kNoLeaf) records[first] = plan.leaves[plan.leaf_at[first]];
    }
    packed_leaves_ = upload_records<GpuPackedLeaf>(dev, records.size(), "the packed leaves", &geometry_bytes_,
                                                   [&](GpuPackedLeaf* out) {
                                                       for (const LeafBlocks::Leaf& l : records)
                                                           *out++ = {l.first_block, l.block_count, l.first_sphere,
                                                                     l.sphere_count};
                                                   });
    packed_bvh_nodes_ = upload_records<GpuBvhNode>(dev, packed_nodes.size(), "the packed BVH nodes", &geometry_bytes_,
                                                   [&](GpuBvhNode* out) {
                                                       std::memcpy(static_cast<void*>(out), packed_nodes.data(),
                                                                   packed_nodes.size() * sizeof(GpuBvhNode));
                                                   });
    leaf_blocks_ = upload_records<Block>(dev, plan.block_count(), "the packed leaves' triangles", &geometry_bytes_,
                                         [&](Block* out) {
                                             for (std::size_t b = 0; b < plan.block_count(); ++b) {
                                                 Block d{};
                                                 d.lanes = plan.block_lanes[b];
                                                 for (int lane = 0; lane < KDRT_LEAF_LANES; ++lane) {
                                                     const std::uint32_t id = plan.block_ids[b * KDRT_LEAF_LANES + lane];
                                                     const auto& t = g.triangles[id - sphere_count];
                                                     const glm::vec<3, Real>* vertex[3] = {&t.v0, &t.v1, &t.v2};
                                                     for (int v = 0; v < 3; ++v)
                                                         for (int a = 0; a < 3; ++a) d.v[v][a][lane] = (*vertex[v])[a];
                                                     d.id[lane] = static_cast<std::int32_t>(id);
                                                 }
                                                 *out++ = d;
                                             }
                                         });
    leaf_spheres_ = upload_array(dev, plan.spheres, "the packed leaves' spheres", &geometry_bytes_);
}

template <class Real>
void ClSceneBuffers::upload_shading_in(const ClDeviceContext& dev, const PreparedScene& scene) {
    using Light = typename GpuRecords<Real>::Light;
    materials_ = upload_records<GpuMaterial>(dev, scene.materials.size(), "the materials", &shading_bytes_,
                                             [&](GpuMaterial* out) {
                                                 for (const Material& m : scene.materials) {
                                                     GpuMaterial d{};
                                                     put3(d.color, m.color);
                                                     d.diffuse = static_cast<float>(m.diffuse);
                                                     d.specular = static_cast<float>(m.specular);
                                                     d.shininess = static_cast<float>(m.shininess);
                                                     d.reflect = static_cast<float>(m.reflect);
                                                     d.transmit = static_cast<float>(m.transmit);
                                                     d.ior = static_cast<float>(m.ior);
                                                     *out++ = d;
                                                 }
                                             });
    lights_ = upload_records<Light>(dev, scene.lights.size(), "the lights", &shading_bytes_, [&](Light* out) {
        for (const PointLight& l : scene.lights) {
            Light d{};
            put3(d.position, l.position);
            put3(d.color, l.color);
            *out++ = d;
        }
    });
    put3(info_.background, scene.settings.background);
    put3(info_.ambient, scene.settings.ambient);
    info_.light_count = static_cast<std::uint32_t>(scene.lights.size());
}

void ClSceneBuffers::upload_id_map(const ClDeviceContext& device, const std::vector<std::uint32_t>& public_ids) {
    std::uint64_t bytes = 0;
    id_map_ = upload_array(device, public_ids, "the object id table", &bytes);
    has_id_map_ = !public_ids.empty();
}

cl_uint ClSceneBuffers::set_scene_args(cl::Kernel& kernel) const {
    cl_uint a = 0;
    for (const cl::Buffer* b : {&spheres_, &triangles_, &normals_, &materials_, &lights_, &nodes_, &leaf_objects_,
                                &ropes_, &bvh_nodes_, &packed_bvh_nodes_, &packed_leaves_, &leaf_blocks_,
                                &leaf_spheres_})
        kernel.setArg(a++, *b);
    kernel.setArg(a++, info_);
    return a;
}

}  // namespace kdrt::detail::ocl
