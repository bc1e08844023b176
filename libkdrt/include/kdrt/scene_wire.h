// A kdrt::Scene as bytes: every field (geometry, materials, lights, camera,
// settings, name and the add_* record `added`, so object ids survive), for
// sending a scene to another process (the cluster build's broadcast) or
// keeping it beside a tree file. Format documented in src/scene/scene_wire.cpp.
#pragma once

#include <kdrt/export.h>
#include <kdrt/scene.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace kdrt {

// Encodes `scene` as it is (no validation: a scene that validate() refuses
// encodes, and is refused when decoded).
KDRT_API std::vector<std::uint8_t> serialize_scene(const Scene& scene);

// Decodes bytes written by serialize_scene: checks the magic, version, every
// length against the bytes left, the checksum, then runs kdrt::validate.
// Damaged, truncated or foreign bytes are an Error(InvalidScene) naming
// `origin` and the problem; nothing is allocated beyond what the bytes hold.
KDRT_API Scene deserialize_scene(const std::uint8_t* data, std::size_t size, const std::string& origin = "<memory>");

}  // namespace kdrt
