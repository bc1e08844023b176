// import_model's front door: what can be checked without parsing the file
// (extension, transform, a regular non-empty file), then the import where
// ImportOptions::isolation says: in the kdrt-import helper (import_process.h)
// or in this process (assimp_import.h).
#include "common/printable_text.h"
#include "scene/affine_transform.h"
#include "scene/assimp_import.h"
#include "scene/import_process.h"
#include "scene/model_file.h"

#include <kdrt/error.h>
#include <kdrt/model_import.h>

#include <algorithm>
#include <string>
#include <system_error>

namespace kdrt {
namespace {

void check_readable(const std::filesystem::path& path, const detail::ModelFailure& fail) {
    std::error_code ec;
    const auto status = std::filesystem::status(path, ec);
    if (ec || !std::filesystem::exists(status)) fail("cannot open: no such file", ErrorCode::Io);
    if (std::filesystem::is_directory(status)) fail("is a directory, not a model file", ErrorCode::Io);
    if (!std::filesystem::is_regular_file(status)) fail("not a regular file", ErrorCode::Io);
    const std::uintmax_t size = std::filesystem::file_size(path, ec);
    if (ec) fail("cannot read the file size: " + ec.message(), ErrorCode::Io);
    if (size == 0) fail("empty file");
}

}  // namespace

const std::vector<std::string>& model_file_extensions() {
    // The formats Assimp reads well, also when they are corrupt, and that are
    // tested (docs/IMPORT.md). Not Collada: Assimp 5.2's reader exhausts the
    // memory on some corrupt files before it fails.
    static const std::vector<std::string> extensions{"obj", "gltf", "glb", "ply", "stl", "off", "fbx"};
    return extensions;
}

bool is_model_file(const std::filesystem::path& path) {
    const std::string ext = detail::lower_extension(path);
    const auto& known = model_file_extensions();
    return std::find(known.begin(), known.end(), ext) != known.end();
}

ImportedModel import_model(const std::filesystem::path& path, const std::array<double, 16>& transform,
                           const ImportOptions& options) {
    // A NUL would cut the path short for the file system and every message: named printably instead.
    if (path.native().find('\0') != std::string::npos)
        throw Error(ErrorCode::Io, detail::printable(path.native(), 200) + ": a path cannot contain a NUL byte");
    const detail::ModelFailure fail(path);
    if (!is_model_file(path)) {
        std::string list;
        for (const std::string& e : model_file_extensions()) list += (list.empty() ? "." : ", .") + e;
        fail("not a model format kdrt imports (by extension: " + list + ")", ErrorCode::Unsupported);
    }
    if (const std::string problem = detail::affine_transform_problem(transform); !problem.empty())
        fail("transform: " + problem, ErrorCode::InvalidArgument);
    if (!(options.time_limit_s >= 0.0))
        fail("ImportOptions::time_limit_s must be 0 (none) or positive", ErrorCode::InvalidArgument);
    check_readable(path, fail);
    if (options.isolation == ImportIsolation::InProcess) return detail::import_with_assimp(path, transform, options);
    return detail::import_in_child_process(path, transform, options);
}

}  // namespace kdrt
