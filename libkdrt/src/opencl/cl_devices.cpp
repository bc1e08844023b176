#include "opencl/cl_devices.h"

#include "common/terminal_text.h"
#include "opencl/cl_error.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <sstream>

namespace kdrt::detail::ocl {

namespace {

std::string trimmed(std::string s) {
    // Some drivers pad names with spaces or leave a trailing NUL.
    auto is_space = [](unsigned char c) { return std::isspace(c) != 0 || c == '\0'; };
    while (!s.empty() && is_space(static_cast<unsigned char>(s.back()))) s.pop_back();
    std::size_t first = 0;
    while (first < s.size() && is_space(static_cast<unsigned char>(s[first]))) ++first;
    return s.substr(first);
}

std::string lowercase(std::string s) {
    for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

const char* type_name(cl_device_type type) {
    // A device may also carry CL_DEVICE_TYPE_DEFAULT; the kind is the rest.
    if ((type & CL_DEVICE_TYPE_GPU) != 0) return "gpu";
    if ((type & CL_DEVICE_TYPE_CPU) != 0) return "cpu";
    if ((type & CL_DEVICE_TYPE_ACCELERATOR) != 0) return "accelerator";
    if ((type & CL_DEVICE_TYPE_CUSTOM) != 0) return "custom";
    return "unknown";
}

bool has_extension(const std::string& extensions, const std::string& name) {
    std::istringstream in(extensions);
    std::string word;
    while (in >> word) {
        if (word == name) return true;
    }
    return false;
}

bool shares_host_memory(const cl::Device& device) {
    cl_bool unified = CL_FALSE;
    // Deprecated since OpenCL 2.0 but answered by 1.2 devices; a device that
    // does not answer is treated as having memory of its own.
    if (clGetDeviceInfo(device(), CL_DEVICE_HOST_UNIFIED_MEMORY, sizeof unified, &unified, nullptr) != CL_SUCCESS)
        return false;
    return unified == CL_TRUE;
}

DeviceInfo describe(const cl::Platform& platform, const cl::Device& device, std::size_t index) {
    DeviceInfo info;
    info.id = "opencl:" + std::to_string(index);
    info.platform = trimmed(platform.getInfo<CL_PLATFORM_NAME>());
    info.name = trimmed(device.getInfo<CL_DEVICE_NAME>());
    info.vendor = trimmed(device.getInfo<CL_DEVICE_VENDOR>());
    info.type = type_name(device.getInfo<CL_DEVICE_TYPE>());
    info.driver_version = trimmed(device.getInfo<CL_DRIVER_VERSION>());
    info.compute_units = device.getInfo<CL_DEVICE_MAX_COMPUTE_UNITS>();
    info.global_memory = device.getInfo<CL_DEVICE_GLOBAL_MEM_SIZE>();
    info.max_allocation = device.getInfo<CL_DEVICE_MAX_MEM_ALLOC_SIZE>();
    info.fp64 = has_extension(device.getInfo<CL_DEVICE_EXTENSIONS>(), "cl_khr_fp64");
    if (!info.fp64) {
        // OpenCL 1.2 made double precision core but optional: a device
        // without the extension string may still report a capability set.
        try {
            info.fp64 = device.getInfo<CL_DEVICE_DOUBLE_FP_CONFIG>() != 0;
        } catch (const cl::Error&) {
            info.fp64 = false;  // a 1.0/1.1 device without cl_khr_fp64 may reject the query
        }
    }
    return info;
}

std::string describe_available(const std::vector<DeviceInfo>& devices) {
    if (devices.empty()) {
        return "no OpenCL platform was found (is an OpenCL driver/ICD installed, "
               "e.g. pocl-opencl-icd?); use --device cpu for the C++ reference renderer";
    }
    std::string text = "available OpenCL devices:";
    for (const DeviceInfo& d : devices) {
        text += "\n  " + d.id + "  " + escape_for_terminal(d.name) + " [" + escape_for_terminal(d.type) + ", " +
                escape_for_terminal(d.platform) + "]";
    }
    return text;
}

[[noreturn]] void throw_unknown(const std::string& spec, const std::string& why,
                                const std::vector<DeviceInfo>& devices) {
    // The spec comes from --device or $KDRT_DEVICE: printed escaped.
    std::string message = "cannot select OpenCL device '" + escape_for_terminal(spec) + "': ";
    if (!why.empty()) message += escape_for_terminal(why) + "; ";
    throw Error(ErrorCode::Device, message + describe_available(devices));
}

// "12.50 MiB (13107200 bytes)": MiB to read, bytes because two sizes a few
// bytes apart print as the same MiB.
std::string size_text(std::uint64_t bytes) {
    char mib[64];
    std::snprintf(mib, sizeof mib, "%.2f MiB", static_cast<double>(bytes) / (1024.0 * 1024.0));
    return std::string(mib) + " (" + std::to_string(bytes) + " bytes)";
}

std::string device_text(const ClDevice& device) {
    return device.info.id + " (" + device.info.name + ")";
}

bool all_digits(const std::string& s) {
    return !s.empty() && std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isdigit(c) != 0; });
}

}  // namespace

std::vector<ClDevice> enumerate_devices() {
    std::vector<ClDevice> result;
    std::vector<cl::Platform> platforms;
    try {
        cl::Platform::get(&platforms);
    } catch (const cl::Error&) {
        return result;  // no ICD loader target, CL_PLATFORM_NOT_FOUND_KHR, ...
    } catch (const std::exception&) {
        return result;
    }
    for (const cl::Platform& platform : platforms) {
        std::vector<cl::Device> devices;
        try {
            platform.getDevices(CL_DEVICE_TYPE_ALL, &devices);
        } catch (const cl::Error&) {
            continue;  // CL_DEVICE_NOT_FOUND: a platform without devices
        }
        for (const cl::Device& device : devices) {
            try {
                ClDevice d{platform, device, describe(platform, device, result.size()), shares_host_memory(device)};
                result.push_back(std::move(d));
            } catch (const cl::Error&) {
                // A device that cannot describe itself is unusable; skipping it
                // keeps the ids of the others dense and stable.
            }
        }
    }
    return result;
}

ClDevice describe_application_device(const cl::Device& device) {
    const cl::Platform platform(device.getInfo<CL_DEVICE_PLATFORM>(), true);
    std::string id = "opencl:app";
    const std::vector<ClDevice> all = enumerate_devices();
    for (const ClDevice& d : all)
        if (d.device() == device()) id = d.info.id;
    DeviceInfo info = describe(platform, device, 0);
    info.id = id;
    return ClDevice{platform, device, std::move(info), shares_host_memory(device)};
}

std::size_t select_device_index(const std::string& spec, const std::vector<DeviceInfo>& devices) {
    const std::string prefix = "opencl";
    const std::string lower = lowercase(spec);
    if (lower.compare(0, prefix.size(), prefix) != 0 ||
        (lower.size() > prefix.size() && lower[prefix.size()] != ':')) {
        throw_unknown(spec,
                      "not an OpenCL device spec (opencl, opencl:N, opencl:gpu, opencl:cpu, opencl:<name>)",
                      devices);
    }
    if (devices.empty()) throw_unknown(spec, "", devices);

    auto first_of_type = [&](const std::string& type) -> std::ptrdiff_t {
        auto it = std::find_if(devices.begin(), devices.end(), [&](const DeviceInfo& d) { return d.type == type; });
        return it == devices.end() ? -1 : it - devices.begin();
    };

    if (lower.size() == prefix.size()) {
        for (const char* type : {"gpu", "cpu"}) {
            if (std::ptrdiff_t i = first_of_type(type); i >= 0) return static_cast<std::size_t>(i);
        }
        return 0;
    }

    const std::string rest = spec.substr(prefix.size() + 1);
    const std::string rest_lower = lowercase(rest);
    if (rest.empty()) throw_unknown(spec, "nothing after 'opencl:'", devices);

    if (all_digits(rest)) {
        std::size_t index = devices.size();
        if (rest.size() <= 9) index = static_cast<std::size_t>(std::stoul(rest));
        if (index >= devices.size()) {
            throw_unknown(spec,
                          "index " + rest + " is out of range 0.." + std::to_string(devices.size() - 1), devices);
        }
        return index;
    }

    if (rest_lower == "gpu" || rest_lower == "cpu" || rest_lower == "accelerator") {
        if (std::ptrdiff_t i = first_of_type(rest_lower); i >= 0) return static_cast<std::size_t>(i);
        throw_unknown(spec, "no device of type " + rest_lower, devices);
    }

    for (std::size_t i = 0; i < devices.size(); ++i) {
        const DeviceInfo& d = devices[i];
        for (const std::string* field : {&d.name, &d.vendor, &d.platform}) {
            if (lowercase(*field).find(rest_lower) != std::string::npos) return i;
        }
    }
    throw_unknown(spec, "no device name, vendor or platform contains '" + rest + "'", devices);
}

ClDevice select_device(const std::string& spec) {
    std::vector<ClDevice> devices = enumerate_devices();
    std::vector<DeviceInfo> infos;
    infos.reserve(devices.size());
    for (const ClDevice& d : devices) infos.push_back(d.info);
    const std::size_t index = select_device_index(spec, infos);
    // Copying retains the device, an OpenCL call that can fail in principle.
    return guard_cl("selecting OpenCL device " + escape_for_terminal(spec), [&] { return devices[index]; });
}

void check_allocation(const ClDevice& device, std::uint64_t bytes, const std::string& what) {
    if (bytes <= device.info.max_allocation) return;
    throw Error(ErrorCode::Device, what + " needs " + size_text(bytes) + " but the device's largest allocation is " +
                                       size_text(device.info.max_allocation) + " on " + device_text(device) +
                                       "; use a smaller scene or another device");
}

void check_total(const ClDevice& device, std::uint64_t total_bytes) {
    if (total_bytes <= device.info.global_memory) return;
    throw Error(ErrorCode::Device, "the device buffers need " + size_text(total_bytes) + " in total but " +
                                       device_text(device) + " has " + size_text(device.info.global_memory) +
                                       " of global memory; use a smaller scene or another device");
}

}  // namespace kdrt::detail::ocl
