// A frame's outputs: its image and id map written (frame_names.h names them
// when there are several frames) through temporaries beside their targets,
// and what is printed after a frame (warnings, the summary line).
#pragma once

#include "command_line.h"

#include <kdrt/render_result.h>
#include <kdrt/scene.h>

namespace kdrt::cli {

// Warnings, outputs, the summary line (not --stats-json, which the caller
// prints). Returns the milliseconds the outputs took (--stats-json's write_ms).
double finish_frame(const Args& a, const Scene& scene, const RenderResult& r, int frame);

}  // namespace kdrt::cli
