// libFuzzer target: FBX (binary and text) through kdrt::import_model (fuzz_model.h).
#include "fuzz_model.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    kdrt_fuzz::import_as(data, size, "fbx");
    return 0;
}
