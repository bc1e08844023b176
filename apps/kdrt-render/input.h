// The scene a run renders: a scene file (JSON), or a model file rendered as
// it is (docs/IMPORT.md): its camera (--camera N), lights and materials, or
// the documented defaults. Models are imported in the kdrt-import helper
// process; Ctrl-C (and SIGTERM, SIGHUP) stop an import within a tenth of a
// second. Their warnings (a material library not found) are printed.
// --width, --height, --max-depth and --samples replace the scene's own
// settings, so that the scene is committed for them.
#pragma once

#include "command_line.h"

#include <kdrt/scene.h>

namespace kdrt::cli {

Scene load_input(const Args& a);

}  // namespace kdrt::cli
