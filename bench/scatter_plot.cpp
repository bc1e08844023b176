#include "scatter_plot.h"

#include <kdrt/error.h>

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace kdrt::bench {

namespace {

namespace IBA = OIIO::ImageBufAlgo;

struct Canvas {
    OIIO::ImageBuf buf;
    bool text_ok = true;

    void box(int x0, int y0, int x1, int y1, const std::array<float, 3>& c, bool fill = true) {
        IBA::render_box(buf, std::min(x0, x1), std::min(y0, y1), std::max(x0, x1), std::max(y0, y1),
                        OIIO::cspan<float>(c.data(), 3), fill);
    }
    void line(int x0, int y0, int x1, int y1, const std::array<float, 3>& c) {
        IBA::render_line(buf, x0, y0, x1, y1, OIIO::cspan<float>(c.data(), 3));
    }
    void text(int x, int y, const std::string& s, int size, const std::array<float, 3>& c,
              IBA::TextAlignX ax = IBA::TextAlignX::Left) {
        if (!text_ok || s.empty()) return;
        if (!IBA::render_text(buf, x, y, s, size, "DejaVuSans", OIIO::cspan<float>(c.data(), 3), ax)) {
            text_ok = false;
            (void)buf.geterror();
        }
    }
};

// Decades [d0, d1] covering the positive finite values.
void decades(const std::vector<double>& v, int& d0, int& d1) {
    double lo = INFINITY, hi = -INFINITY;
    for (double x : v)
        if (x > 0.0 && std::isfinite(x)) {
            lo = std::min(lo, x);
            hi = std::max(hi, x);
        }
    if (!std::isfinite(lo)) lo = 1.0, hi = 10.0;
    d0 = static_cast<int>(std::floor(std::log10(lo)));
    d1 = std::max(d0 + 1, static_cast<int>(std::ceil(std::log10(hi))));
}

std::string decade_label(int d) {
    char s[32];
    std::snprintf(s, sizeof s, "1e%d", d);
    return s;
}

}  // namespace

bool draw_scatter_plot(const std::filesystem::path& path, const ScatterPlot& plot) {
    const int panel_w = 420, panel_h = 320, cols = std::min<int>(3, std::max<int>(1, static_cast<int>(plot.panels.size())));
    const int rows = (static_cast<int>(plot.panels.size()) + cols - 1) / cols;
    const int header = 40 + 16 * static_cast<int>(plot.subtitle.size()) + 10;
    const int width = cols * panel_w + 40, height = header + rows * (panel_h + 60) + 20;
    Canvas cv{OIIO::ImageBuf(OIIO::ImageSpec(width, height, 3, OIIO::TypeDesc::UINT8))};
    const std::array<float, 3> white{1, 1, 1}, black{0, 0, 0}, grid{0.88f, 0.88f, 0.88f}, dark{0.35f, 0.35f, 0.35f},
        front{0.85f, 0.2f, 0.1f};
    IBA::fill(cv.buf, OIIO::cspan<float>(white.data(), 3));
    cv.text(20, 28, plot.title, 20, black);
    for (std::size_t i = 0; i < plot.subtitle.size(); ++i) cv.text(20, 48 + 16 * static_cast<int>(i), plot.subtitle[i], 12, dark);

    for (std::size_t p = 0; p < plot.panels.size(); ++p) {
        const ScatterPanel& panel = plot.panels[p];
        const int ox = 20 + static_cast<int>(p % cols) * panel_w + 60;
        const int oy = header + static_cast<int>(p / cols) * (panel_h + 60) + 20;
        const int w = panel_w - 90, h = panel_h - 40;
        std::vector<double> xs, ys;
        for (const ScatterPoint& q : panel.points) {
            xs.push_back(q.x);
            ys.push_back(q.y);
        }
        int x0, x1, y0, y1;
        decades(xs, x0, x1);
        decades(ys, y0, y1);
        auto px = [&](double v) { return ox + static_cast<int>(std::lround((std::log10(v) - x0) / (x1 - x0) * w)); };
        auto py = [&](double v) {
            if (!(v > 0.0)) return oy + h;  // an exact result sits on the floor
            return oy + h - static_cast<int>(std::lround((std::log10(v) - y0) / (y1 - y0) * h));
        };
        for (int d = x0; d <= x1; ++d) {
            cv.line(px(std::pow(10.0, d)), oy, px(std::pow(10.0, d)), oy + h, grid);
            cv.text(px(std::pow(10.0, d)), oy + h + 14, decade_label(d), 10, dark, IBA::TextAlignX::Center);
        }
        for (int d = y0; d <= y1; ++d) {
            cv.line(ox, py(std::pow(10.0, d)), ox + w, py(std::pow(10.0, d)), grid);
            cv.text(ox - 4, py(std::pow(10.0, d)) + 4, decade_label(d), 10, dark, IBA::TextAlignX::Right);
        }
        cv.box(ox, oy, ox + w, oy + h, dark, false);
        cv.text(ox, oy - 6, panel.title, 14, black);
        cv.text(ox + w / 2, oy + h + 30, plot.x_label, 11, dark, IBA::TextAlignX::Center);
        cv.text(ox - 55, oy - 6, plot.y_label, 11, dark);

        // The Pareto front, left to right.
        std::vector<const ScatterPoint*> f;
        for (const ScatterPoint& q : panel.points)
            if (q.pareto) f.push_back(&q);
        std::sort(f.begin(), f.end(), [](const ScatterPoint* a, const ScatterPoint* b) { return a->x < b->x; });
        for (std::size_t i = 1; i < f.size(); ++i)
            cv.line(px(f[i - 1]->x), py(f[i - 1]->y), px(f[i]->x), py(f[i]->y), front);
        for (const ScatterPoint& q : panel.points) {
            const int x = px(q.x), y = py(q.y);
            cv.box(x - 3, y - 3, x + 3, y + 3, q.pareto ? front : q.color);
            cv.text(x + 6, y - 4, q.label, 9, dark);
        }
    }
    std::error_code ec;
    if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path(), ec);
    if (!cv.buf.write(path.string())) throw Error(ErrorCode::Io, path.string() + ": " + cv.buf.geterror());
    return cv.text_ok;
}

}  // namespace kdrt::bench
