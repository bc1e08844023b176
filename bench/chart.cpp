#include "chart.h"

#include <kdrt/error.h>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace kdrt::bench {

namespace {

namespace IBA = OIIO::ImageBufAlgo;

constexpr const char* kFont = "DejaVuSans";

struct Canvas {
    OIIO::ImageBuf buf;
    bool text_ok = true;

    void box(int x0, int y0, int x1, int y1, const std::array<float, 3>& c, bool fill = true) {
        if (x1 < x0) std::swap(x0, x1);
        if (y1 < y0) std::swap(y0, y1);
        IBA::render_box(buf, x0, y0, x1, y1, OIIO::cspan<float>(c.data(), 3), fill);
    }
    void text(int x, int y, const std::string& s, int size, const std::array<float, 3>& c,
              IBA::TextAlignX ax = IBA::TextAlignX::Left, IBA::TextAlignY ay = IBA::TextAlignY::Baseline) {
        if (!text_ok || s.empty()) return;
        if (!IBA::render_text(buf, x, y, s, size, kFont, OIIO::cspan<float>(c.data(), 3), ax, ay)) {
            text_ok = false;
            (void)buf.geterror();  // clear the error: the chart goes on without text
        }
    }
};

std::array<float, 3> hsv(float h, float s, float v) {
    const float c = v * s, hp = std::fmod(h, 1.0f) * 6.0f, x = c * (1.0f - std::abs(std::fmod(hp, 2.0f) - 1.0f));
    std::array<float, 3> rgb{0, 0, 0};
    if (hp < 1) rgb = {c, x, 0};
    else if (hp < 2) rgb = {x, c, 0};
    else if (hp < 3) rgb = {0, c, x};
    else if (hp < 4) rgb = {0, x, c};
    else if (hp < 5) rgb = {x, 0, c};
    else rgb = {c, 0, x};
    const float m = v - c;
    return {rgb[0] + m, rgb[1] + m, rgb[2] + m};
}

}  // namespace

std::array<float, 3> series_color(int family, int i, int n) {
    const float f = n > 1 ? static_cast<float>(i) / static_cast<float>(n - 1) : 0.5f;
    switch (family) {
        case 0: return hsv(0.58f, 0.35f + 0.6f * f, 0.95f - 0.45f * f);  // blues
        case 1: return hsv(0.07f, 0.35f + 0.6f * f, 1.0f - 0.35f * f);   // oranges
        case 2: return hsv(0.33f, 0.35f + 0.6f * f, 0.85f - 0.4f * f);   // greens
        case 4: return hsv(0.8f, 0.5f + 0.4f * f, 0.8f - 0.3f * f);      // purples
        default: {
            const float g = 0.8f - 0.6f * f;
            return {g, g, g};
        }
    }
}

bool draw_bar_chart(const std::filesystem::path& path, const BarChart& chart) {
    const int groups = static_cast<int>(chart.groups.size());
    const int nseries = static_cast<int>(chart.series.size());
    const int legend_cols = 3, legend_rows = (nseries + legend_cols - 1) / legend_cols;
    const int width = std::max(900, 140 + groups * std::max(120, nseries * 12 + 24));
    const int top = 40 + 16 * static_cast<int>(chart.subtitle.size()) + 20, plot_h = 460;
    const int left = 80, right = 20, bottom_axis = top + plot_h;
    const int height = bottom_axis + 40 + legend_rows * 20 + 20;
    Canvas cv{OIIO::ImageBuf(OIIO::ImageSpec(width, height, 3, OIIO::TypeDesc::UINT8))};
    const std::array<float, 3> white{1, 1, 1}, black{0, 0, 0}, grid{0.85f, 0.85f, 0.85f}, dark{0.3f, 0.3f, 0.3f};
    IBA::fill(cv.buf, OIIO::cspan<float>(white.data(), 3));

    // The decades that hold every value.
    double lo = INFINITY, hi = -INFINITY;
    for (const ChartSeries& s : chart.series)
        for (double v : s.values)
            if (v > 0.0 && std::isfinite(v)) {
                lo = std::min(lo, v);
                hi = std::max(hi, v);
            }
    if (!std::isfinite(lo)) lo = 1.0, hi = 10.0;
    const int d0 = static_cast<int>(std::floor(std::log10(lo))), d1 = std::max(d0 + 1, static_cast<int>(std::ceil(std::log10(hi))));
    auto y_of = [&](double v) {
        const double f = (std::log10(v) - d0) / (d1 - d0);
        return bottom_axis - static_cast<int>(std::lround(f * plot_h));
    };

    cv.text(left, 28, chart.title, 20, black);
    for (std::size_t i = 0; i < chart.subtitle.size(); ++i)
        cv.text(left, 48 + 16 * static_cast<int>(i), chart.subtitle[i], 12, dark);
    for (int d = d0; d <= d1; ++d) {
        const int y = y_of(std::pow(10.0, d));
        cv.box(left, y, width - right, y, grid);
        char label[32];
        std::snprintf(label, sizeof label, d >= 0 && d < 7 ? "%.0f" : "1e%.0f", d >= 0 && d < 7 ? std::pow(10.0, d) : d * 1.0);
        cv.text(left - 6, y + 4, label, 12, dark, IBA::TextAlignX::Right);
    }
    cv.text(8, top - 6, chart.y_label, 12, dark);
    cv.box(left, top, left, bottom_axis, dark);
    cv.box(left, bottom_axis, width - right, bottom_axis, dark);

    const int group_w = (width - left - right) / std::max(1, groups);
    const int bar_w = std::max(3, std::min(24, (group_w - 16) / std::max(1, nseries)));
    for (int g = 0; g < groups; ++g) {
        const int gx = left + g * group_w + (group_w - bar_w * nseries) / 2;
        for (int s = 0; s < nseries; ++s) {
            const ChartSeries& se = chart.series[static_cast<std::size_t>(s)];
            if (static_cast<std::size_t>(g) >= se.values.size()) continue;
            const double v = se.values[static_cast<std::size_t>(g)];
            if (!(v > 0.0) || !std::isfinite(v)) continue;
            const bool hollow = static_cast<std::size_t>(g) < se.lower_bound.size() && se.lower_bound[static_cast<std::size_t>(g)];
            const int x0 = gx + s * bar_w, x1 = x0 + bar_w - 2;
            const int y = std::max(top, y_of(std::max(v, std::pow(10.0, d0))));
            if (hollow) {
                cv.box(x0, y, x1, bottom_axis - 1, se.color, false);
                cv.box(x0, y, x1, y + 2, se.color);  // a lid: "more than this"
            } else {
                cv.box(x0, y, x1, bottom_axis - 1, se.color);
            }
        }
        cv.text(left + g * group_w + group_w / 2, bottom_axis + 20, chart.groups[static_cast<std::size_t>(g)], 14,
                black, IBA::TextAlignX::Center);
    }

    const int legend_y = bottom_axis + 44, col_w = (width - left - right) / legend_cols;
    for (int s = 0; s < nseries; ++s) {
        const int x = left + (s % legend_cols) * col_w, y = legend_y + (s / legend_cols) * 20;
        const ChartSeries& se = chart.series[static_cast<std::size_t>(s)];
        cv.box(x, y - 11, x + 14, y + 1, se.color);
        cv.text(x + 20, y, se.label, 12, black);
    }

    std::error_code ec;
    if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path(), ec);
    if (!cv.buf.write(path.string())) throw Error(ErrorCode::Io, path.string() + ": " + cv.buf.geterror());
    return cv.text_ok;
}

}  // namespace kdrt::bench
