#include "id_check.h"

#include <algorithm>
#include <cmath>

namespace kdrt::bench {

std::string IdCheck::summary() const {
    if (pixels == 0) return "not checked";
    std::string s = ok() ? "ok" : "FAILED";
    if (mismatches == 0) return s + ", identical";
    s += ", " + std::to_string(mismatches) + " of " + std::to_string(pixels) + " differ (" + std::to_string(edges) +
         " silhouette, " + std::to_string(ties) + " tie";
    if (unexplained) s += ", " + std::to_string(unexplained) + " unexplained";
    return s + ")";
}

IdCheck compare_ids(const IdMap& ref, const IdMap& got) {
    IdCheck c;
    const int W = ref.width, H = ref.height;
    const std::size_t n = static_cast<std::size_t>(W) * H;
    if (got.width != W || got.height != H || ref.ids.size() != n || got.ids.size() != n || ref.t.size() != n ||
        got.t.size() != n) {
        c.pixels = n;
        c.mismatches = c.unexplained = n;  // a map of the wrong size explains nothing
        return c;
    }
    c.pixels = n;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const std::size_t i = static_cast<std::size_t>(y) * W + x;
            if (ref.ids[i] == got.ids[i]) continue;
            ++c.mismatches;
            const bool tie = ref.ids[i] >= 0 && got.ids[i] >= 0 &&
                             std::abs(ref.t[i] - got.t[i]) <= 1e-4f * std::max(ref.t[i], got.t[i]);
            if (tie) {
                ++c.ties;
                continue;
            }
            bool edge = false;
            for (int dy = -1; dy <= 1 && !edge; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int nx = x + dx, ny = y + dy;
                    if (nx < 0 || ny < 0 || nx >= W || ny >= H) continue;
                    if (ref.ids[static_cast<std::size_t>(ny) * W + nx] != ref.ids[i]) {
                        edge = true;
                        break;
                    }
                }
            if (edge) ++c.edges;
            else ++c.unexplained;
        }
    return c;
}

}  // namespace kdrt::bench
