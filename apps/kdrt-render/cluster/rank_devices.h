// The devices a rank renders on: --device as in a single process (one name, a
// comma-separated list, "all"), where "local-rank" stands for the rank's
// number on its host, so that one command line gives each rank of a node its
// own GPU: --device opencl:local-rank opens OpenCL device
// (OMPI_COMM_WORLD_LOCAL_RANK mod the number of OpenCL devices).
#pragma once

#include <kdrt/device.h>

#include <string>
#include <vector>

namespace kdrt::cluster {

// The list with "local-rank" replaced by the OpenCL device number for this rank.
std::string device_list_for_rank(const std::string& list, int local_rank);

// Opens them; an Error(Device) names the list and the problem.
std::vector<Device> open_rank_devices(const std::string& list, int local_rank);

}  // namespace kdrt::cluster
