// ImportIsolation::ChildProcess: the import runs in the kdrt-import helper
// (src/scene/import_helper/kdrt_import.cpp), started with posix_spawn (safe
// in a process that already runs threads, unlike fork), which sends the
// model back on a pipe (model_wire.h). The helper lives within an address
// space limit (RLIMIT_AS) and a CPU-time limit, dumps no core and dies with
// its parent; this side enforces the wall-clock limit and polls
// ImportOptions::keep_going, killing the helper to stop it. A helper that
// crashes or aborts (a parser bug no bound foresaw) is an Error naming the
// file and the signal; the calling process goes on.
//
// The helper is looked for as $KDRT_IMPORT_HELPER, in the build tree for
// programs run from there, then relative to libkdrt (or the program it is
// linked into) and in the installed libexec directory.
#pragma once

#include <kdrt/model_import.h>

#include <array>
#include <cstdint>
#include <filesystem>

namespace kdrt::detail {

ImportedModel import_in_child_process(const std::filesystem::path& path, const std::array<double, 16>& transform,
                                      const ImportOptions& options);

// ImportOptions::memory_limit's default: half the physical memory, at most 16 GiB.
std::uint64_t default_import_memory_limit();

}  // namespace kdrt::detail
