#include "opencl/kernel_resources.h"

#include "device/kernel_records.h"

#include <algorithm>

namespace kdrt::detail::ocl {

std::vector<KernelResources> kernel_resources(const cl::Program& program, const cl::Device& device) {
    std::vector<cl::Kernel> kernels;
    cl::Program(program).createKernels(&kernels);  // a handle copy: createKernels is not const
    std::vector<KernelResources> out;
    out.reserve(kernels.size());
    for (const cl::Kernel& k : kernels) {
        KernelResources r;
        r.kernel = k.getInfo<CL_KERNEL_FUNCTION_NAME>();
        // Some implementations pad the name with a terminating NUL.
        while (!r.kernel.empty() && r.kernel.back() == '\0') r.kernel.pop_back();
        r.private_bytes = k.getWorkGroupInfo<CL_KERNEL_PRIVATE_MEM_SIZE>(device);
        r.local_bytes = k.getWorkGroupInfo<CL_KERNEL_LOCAL_MEM_SIZE>(device);
        r.work_group_size = k.getWorkGroupInfo<CL_KERNEL_WORK_GROUP_SIZE>(device);
        r.preferred_multiple = k.getWorkGroupInfo<CL_KERNEL_PREFERRED_WORK_GROUP_SIZE_MULTIPLE>(device);
        out.push_back(std::move(r));
    }
    std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.kernel < b.kernel; });
    return out;
}

// The stack of the walk a work-item traces with. Budget: about 256 bytes per
// work-item of private arrays is what NVIDIA and AMD GPUs keep in registers at
// useful occupancy (with the ray, the hit and the 64-byte mailbox besides);
// beyond it the stack spills to slow off-chip memory.
// - The kd-tree's full stack (KDRT_MAX_TREE_DEPTH + 2 = 66 entries: 792 B in
//   float, 1320 B in double) is far over it, which is what the short stack
//   (KDRT_SHORT_STACK_SIZE = 4 entries: 48 B / 80 B) is for; restart and ropes
//   keep no stack. CPU devices walk four rays as a packet (cl/traverse_packet.cl):
//   66 entries of node, lanes and four tmin and tmax (2640 B / 4752 B).
// - The BVH's on GPUs: one entry of node and slot list per level,
//   KDRT_BVH_SLOT_STACK_SIZE = 64 entries (512 B in either precision), twice
//   the budget. On CPU devices the C++ twin's sorted stack for a packet of four
//   rays (cl/traverse_bvh_packet.cl), KDRT_BVH_SORTED_STACK_SIZE = 449 entries
//   of four entry distances, child, count, lanes and nearest entry (14368 B /
//   25144 B), which PoCL keeps on the thread's stack.
std::uint64_t traversal_stack_bytes(const KernelVariant& variant) {
    const std::uint64_t real = variant.precision == Precision::Double ? sizeof(double) : sizeof(float);
    const std::uint64_t word = sizeof(std::uint32_t);
    const bool packets = rays_per_work_item(variant) > 1;
    if (walks_bvh(variant)) {
        if (!packets) return KDRT_BVH_SLOT_STACK_SIZE * 2 * word;
        // BvhPacketEntry: t[4], child, count, lanes, nearest, padded to a real's alignment.
        const std::uint64_t entry = (5 * real + 3 * word + real - 1) / real * real;
        return KDRT_BVH_SORTED_STACK_SIZE * entry;
    }
    switch (variant.traversal) {
        case Traversal::Stack:  // node and tmin, tmax; a packet's: node, lanes and four of each
            return (KDRT_MAX_TREE_DEPTH + 2) * (packets ? 2 * word + 8 * real : word + 2 * real);
        case Traversal::ShortStack: return (word + 2 * real) * KDRT_SHORT_STACK_SIZE;
        case Traversal::None:
        case Traversal::Restart:
        case Traversal::Ropes: return 0;
    }
    return 0;
}

}  // namespace kdrt::detail::ocl
