// libFuzzer target: glTF through kdrt::import_model (fuzz_model.h). Inputs
// that start with "glTF" are binary glTF (.glb), others glTF JSON (.gltf).
#include "fuzz_model.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const bool binary = size >= 4 && data[0] == 'g' && data[1] == 'l' && data[2] == 'T' && data[3] == 'F';
    kdrt_fuzz::import_as(data, size, binary ? "glb" : "gltf");
    return 0;
}
