#include <kdrt/id_map.h>

#include <algorithm>
#include <cmath>

namespace kdrt {

std::string IdMapComparison::summary() const {
    if (pixels == 0) return "not checked";
    std::string s = ok() ? "ok" : "FAILED";
    if (mismatches == 0) return s + ", identical";
    s += ", " + std::to_string(mismatches) + " of " + std::to_string(pixels) + " differ (" + std::to_string(edges) +
         " silhouette, " + std::to_string(ties) + " tie";
    if (unexplained) s += ", " + std::to_string(unexplained) + " unexplained";
    return s + ")";
}

IdMapComparison compare_id_maps(int W, int H, std::span<const std::int32_t> ref_ids, std::span<const float> ref_t,
                                std::span<const std::int32_t> ids, std::span<const float> t) {
    IdMapComparison c;
    const std::size_t n = static_cast<std::size_t>(std::max(W, 0)) * static_cast<std::size_t>(std::max(H, 0));
    c.pixels = n;
    if (ref_ids.size() != n || ids.size() != n || ref_t.size() != n || t.size() != n) {
        c.mismatches = c.unexplained = std::max<std::size_t>(n, 1);  // a map of the wrong size explains nothing
        c.pixels = std::max<std::size_t>(n, 1);
        return c;
    }
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const std::size_t i = static_cast<std::size_t>(y) * W + x;
            if (ref_ids[i] == ids[i]) continue;
            ++c.mismatches;
            if (ref_ids[i] >= 0 && ids[i] >= 0 && std::abs(ref_t[i] - t[i]) <= 1e-4f * std::max(ref_t[i], t[i])) {
                ++c.ties;
                continue;
            }
            bool edge = false;
            for (int dy = -1; dy <= 1 && !edge; ++dy)
                for (int dx = -1; dx <= 1 && !edge; ++dx) {
                    const int nx = x + dx, ny = y + dy;
                    if (nx < 0 || ny < 0 || nx >= W || ny >= H) continue;
                    edge = ref_ids[static_cast<std::size_t>(ny) * W + nx] != ref_ids[i];
                }
            if (edge) ++c.edges;
            else ++c.unexplained;
        }
    return c;
}

IdMapComparison compare_id_maps(const RenderResult& reference, const RenderResult& candidate) {
    if (candidate.image.width != reference.image.width || candidate.image.height != reference.image.height) {
        IdMapComparison c;
        c.pixels = c.mismatches = c.unexplained = std::max<std::size_t>(reference.ids.size(), 1);
        return c;
    }
    return compare_id_maps(reference.image.width, reference.image.height, reference.ids, reference.hit_t,
                           candidate.ids, candidate.hit_t);
}

}  // namespace kdrt
