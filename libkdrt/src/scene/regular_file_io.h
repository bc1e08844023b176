// The file access Assimp gets while importing a model: regular files only (a
// glTF buffer URI naming a FIFO or /dev/zero must not hang or exhaust memory),
// a record of the files that were asked for but missing, so that a material
// library that is not there becomes a warning instead of silence, and the
// closing of streams Assimp forgets (its glTF reader leaks one when a buffer
// is shorter than declared) when the importer is done.
#pragma once

#include <assimp/DefaultIOSystem.h>

#include <set>
#include <string>
#include <vector>

namespace kdrt::detail {

class RegularFileIo : public Assimp::DefaultIOSystem {
public:
    RegularFileIo() = default;
    RegularFileIo(const RegularFileIo&) = delete;
    RegularFileIo& operator=(const RegularFileIo&) = delete;
    ~RegularFileIo() override;  // closes the streams still open

    bool Exists(const char* file) const override;
    Assimp::IOStream* Open(const char* file, const char* mode = "rb") override;
    void Close(Assimp::IOStream* stream) override;

    // Paths that Assimp looked for but that are not regular files, in order, once each.
    const std::vector<std::string>& missing() const { return missing_; }

    // Streams unregister themselves when Assimp deletes them (by Close or directly).
    void forget(Assimp::IOStream* stream) { open_.erase(stream); }

private:
    void note_missing(const std::string& file) const;
    mutable std::vector<std::string> missing_;
    std::set<Assimp::IOStream*> open_;
};

}  // namespace kdrt::detail
