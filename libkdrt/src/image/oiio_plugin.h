// Loading libkdrt's OpenImageIO plugin (oiio_plugin/plugin_abi.h) on first use.
#pragma once

#include "image/oiio_plugin/plugin_abi.h"

#include <string>

namespace kdrt::detail {

// The plugin, loaded once. Looked for: $KDRT_OIIO_PLUGIN (a file) when set;
// else the build tree's copy when this code runs from the build tree; else
// next to the object holding libkdrt (libkdrt.so, or the program it is linked
// into), in the install libdir relative to the program, and in the install
// libdir. Throws kdrt::Error(Io) naming `why` ("writing .exr images") and the
// places looked in when it is missing or unusable.
const KdrtOiioPlugin& oiio_plugin(const std::string& why);

}  // namespace kdrt::detail
