// The file access Assimp gets while importing a model: regular files only (a
// glTF buffer URI naming a FIFO or /dev/zero must not hang or exhaust memory),
// and a record of the files that were asked for but missing, so that a
// material library that is not there becomes a warning instead of silence.
#pragma once

#include <assimp/DefaultIOSystem.h>

#include <string>
#include <vector>

namespace kdrt::detail {

class RegularFileIo : public Assimp::DefaultIOSystem {
public:
    bool Exists(const char* file) const override;
    Assimp::IOStream* Open(const char* file, const char* mode = "rb") override;

    // Paths that Assimp looked for but that are not regular files, in order, once each.
    const std::vector<std::string>& missing() const { return missing_; }

private:
    void note_missing(const std::string& file) const;
    mutable std::vector<std::string> missing_;
};

}  // namespace kdrt::detail
