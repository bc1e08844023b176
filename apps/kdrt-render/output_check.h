// Every file a run will write, checked before any work: each frame's image
// and id map (frame_names.h), the saved tree. Each must be writable (a
// writable directory, no symbolic link or special file to replace: Io
// errors of check_output_target), and none may be an input or another
// output, by name or by inode (a hard link): writing it would destroy it.
// Failures are UsageErrors (exit 2) naming the option and the file.
#pragma once

#include "command_line.h"

namespace kdrt::cli {

void check_outputs(const Args& a);

}  // namespace kdrt::cli
