// --stats-json and --tree-stats: a frame's statistics as JSON.
#pragma once

#include "command_line.h"

#include <kdrt/bvh_config.h>
#include <kdrt/kd_tree.h>
#include <kdrt/render.h>
#include <kdrt/render_result.h>
#include <kdrt/scene.h>

#include <nlohmann/json.hpp>

namespace kdrt::cli {

nlohmann::ordered_json tree_stats_json(const KdTreeStats& s);
nlohmann::ordered_json bvh_stats_json(const BvhStats& s);

// The --stats-json object of one frame; write_ms: encoding and writing its outputs.
nlohmann::ordered_json stats_json(const Args& a, const Scene& scene, const RenderOptions& o, const RenderResult& r,
                                  const TileSize& tile, double write_ms);

// Prints a frame's JSON line on stdout, "frame" added when there are several.
void print_stats(const Args& a, nlohmann::ordered_json j, int frame);

}  // namespace kdrt::cli
