// The file access Assimp gets while importing a model: regular files only (a
// glTF buffer URI naming a FIFO or /dev/zero must not hang or exhaust memory),
// inside the model's folder unless allowed otherwise (a buffer URI
// "../../secret.bin" reads nothing outside it; symbolic links are resolved),
// a record of the files that were asked for but missing, so that a material
// library that is not there becomes a warning instead of silence, and the
// closing of streams Assimp forgets (its glTF reader leaks one when a buffer
// is shorter than declared) when the importer is done.
#pragma once

#include <assimp/DefaultIOSystem.h>

#include <filesystem>
#include <set>
#include <string>
#include <vector>

namespace kdrt::detail {

class RegularFileIo : public Assimp::DefaultIOSystem {
public:
    // `model`: the file being imported; others are opened only inside its
    // folder and subfolders unless `allow_outside`.
    RegularFileIo(const std::filesystem::path& model, bool allow_outside);
    RegularFileIo(const RegularFileIo&) = delete;
    RegularFileIo& operator=(const RegularFileIo&) = delete;
    ~RegularFileIo() override;  // closes the streams still open

    bool Exists(const char* file) const override;
    Assimp::IOStream* Open(const char* file, const char* mode = "rb") override;
    void Close(Assimp::IOStream* stream) override;

    // Paths that Assimp looked for but that are not regular files, in order, once each.
    const std::vector<std::string>& missing() const { return missing_; }
    // Paths that Assimp looked for outside the model's folder, not opened.
    const std::vector<std::string>& refused() const { return refused_; }

    // Streams unregister themselves when Assimp deletes them (by Close or directly).
    void forget(Assimp::IOStream* stream) { open_.erase(stream); }

private:
    void note_missing(const std::string& file) const;
    bool allowed(const char* file) const;  // notes a refused file
    std::filesystem::path model_, folder_;
    bool allow_outside_;
    mutable std::vector<std::string> missing_, refused_;
    std::set<Assimp::IOStream*> open_;
};

}  // namespace kdrt::detail
