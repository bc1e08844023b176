// OpenCL interoperation: a Device around the application's own context,
// device and queue, and ray queries on the application's cl_mem buffers
// (no copies through the host). This header needs no OpenCL headers and sets
// no CL_TARGET_OPENCL_VERSION: it declares the four handle types it names as
// Khronos' CL/cl.h does, so <CL/cl.h> of any target version may be included
// before or after it.
#pragma once

#include <kdrt/committed_scene.h>
#include <kdrt/device.h>
#include <kdrt/export.h>

#include <cstddef>

// The opaque handles of CL/cl_platform.h and CL/cl.h, declared identically
// (a typedef may be repeated with the same type).
typedef struct _cl_context* cl_context;
typedef struct _cl_device_id* cl_device_id;
typedef struct _cl_command_queue* cl_command_queue;
typedef struct _cl_mem* cl_mem;

namespace kdrt {

// Wraps (and retains) the application's objects; the queue must belong to
// the context and the device, and be in order; the device must compile
// OpenCL C 1.2. Otherwise throws kdrt::Error(Device) naming the problem.
// kdrt enqueues its work on that queue (serialised with a lock inside kdrt;
// the application's own commands on it are not), and queries on host arrays
// on a device with memory of its own also on a second queue it makes in the
// context (their staging; see docs/API.md).
KDRT_API Device wrap_opencl_device(cl_context context, cl_device_id device, cl_command_queue queue);

// Closest hit / any hit of `count` rays: `rays` holds QueryRay[count],
// `hits` receives QueryHit[count] (or unsigned char[count] for occluded). The
// scene must be committed on an OpenCL device with the same context. Returns
// when the results are in the buffers (the work is finished on the queue).
// Buffers of another context, too small for `count`, or not readable
// (rays) / writable (results) by kernels: kdrt::Error(InvalidArgument).
KDRT_API void intersect(const CommittedScene& scene, cl_mem rays, cl_mem hits, std::size_t count);
KDRT_API void occluded(const CommittedScene& scene, cl_mem rays, cl_mem occluded, std::size_t count);

}  // namespace kdrt
