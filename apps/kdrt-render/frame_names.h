// Output names of a --frames render: one file per frame, the frame number
// (zero-padded to 4 digits, more when there are more frames) inserted before
// the extension: out.png -> out_0000.png, out_0001.png, ...; ids.bin ->
// ids_0000.bin. A single frame keeps the name as given.
#pragma once

#include <string>

namespace kdrt::cli {

std::string frame_file_name(const std::string& path, int frame, int frames);

}  // namespace kdrt::cli
