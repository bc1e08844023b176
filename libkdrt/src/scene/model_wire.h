// What the import helper (kdrt-import) sends back on its standard output:
// an ImportedModel, or the kdrt::Error its import raised, as checksummed
// bytes. The model's triangles, materials and lights travel as a scene in
// the scene wire format (kdrt/scene_wire.h), so they are checked and
// validated as any scene bytes are; cameras and statistics follow.
//
//   "KDRTIMPT" | u32 version | u64 payload size | u64 XXH3-64 of the payload | payload
//   payload: u8 kind = 0, u64 n, n scene bytes, u64 cameras, cameras, statistics
//            u8 kind = 1, u64 ErrorCode, string message
//   camera: string name, position, look_at, up (3 x f64 each), f64 fov_y, f64 aspect, u8 orthographic
//   statistics: u64 meshes, skipped_points, skipped_lines, skipped_lights, flat_triangles; u64 n, n strings
//   integers little-endian, f64 as its bits, string: u64 length, bytes.
#pragma once

#include <kdrt/error.h>
#include <kdrt/model_import.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace kdrt::detail {

inline constexpr std::size_t kImportResultHeaderBytes = 28;

std::vector<std::uint8_t> encode_import_result(ImportedModel&& model);
std::vector<std::uint8_t> encode_import_error(ErrorCode code, const std::string& message);

// The payload size a header announces (the header's first 28 bytes), or
// Error(InvalidScene) naming `origin` when it is no result header.
std::uint64_t import_result_payload_size(const std::uint8_t* header, const std::string& origin);

// Whether the bytes are a whole result: header, announced size and checksum.
bool is_complete_import_result(const std::uint8_t* data, std::size_t size);

// The model, or throws the Error the bytes carry; damaged bytes are an
// Error(InvalidScene) naming `origin`.
ImportedModel decode_import_result(const std::uint8_t* data, std::size_t size, const std::string& origin);

}  // namespace kdrt::detail
