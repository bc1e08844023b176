#include "cluster/rank_devices.h"

#include <kdrt/device.h>
#include <kdrt/error.h>
#include <kdrt/tiled_render.h>

#include <algorithm>

namespace kdrt::cluster {

std::string device_list_for_rank(const std::string& list, int local_rank) {
    static const std::string token = "local-rank";
    std::string out = list;
    std::size_t at = out.find(token);
    if (at == std::string::npos) return out;
    const std::vector<DeviceInfo> devices = list_devices();
    const auto opencl = std::count_if(devices.begin(), devices.end(),
                                      [](const DeviceInfo& d) { return d.id.rfind("opencl:", 0) == 0; });
    if (opencl == 0)
        throw Error(ErrorCode::Device, "--device " + list + ": 'local-rank' picks an OpenCL device, and there is none");
    const std::string number = std::to_string(local_rank % opencl);
    for (; at != std::string::npos; at = out.find(token, at + number.size())) out.replace(at, token.size(), number);
    return out;
}

std::vector<Device> open_rank_devices(const std::string& list, int local_rank) {
    const std::string resolved = device_list_for_rank(list, local_rank);
    try {
        if (resolved.find(',') == std::string::npos && resolved != "all") return {Device::open(resolved)};
        return open_devices(resolved);
    } catch (const Error& e) {
        if (resolved == list) throw;
        // The message names the substituted list: say what the user wrote.
        throw Error(e.code(), "--device " + list + " (here " + resolved + "): " + e.what());
    }
}

}  // namespace kdrt::cluster
