// A grouped bar chart on a log scale (one group per scene, one bar per
// configuration), drawn with OpenImageIO's ImageBufAlgo::render_box and
// render_text. When no font can be found the chart is drawn without text and
// the caller puts the legend in the Markdown.
#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <vector>

namespace kdrt::bench {

struct ChartSeries {
    std::string label;
    std::vector<double> values;       // one per group; NaN or <= 0: no bar
    std::vector<bool> lower_bound;    // drawn hollow: the true value is larger (may be empty)
    std::array<float, 3> color{0.3f, 0.3f, 0.3f};
};

struct BarChart {
    std::string title;
    std::vector<std::string> subtitle;  // small lines under the title (machine, date)
    std::string y_label;
    std::vector<std::string> groups;
    std::vector<ChartSeries> series;
};

// Writes the chart as PNG. Returns true when the text could be drawn too.
bool draw_bar_chart(const std::filesystem::path& path, const BarChart& chart);

// A colour for series i of n in family f (0: blues, 1: oranges, 2: greens, 3: greys, 4: purples).
std::array<float, 3> series_color(int family, int i, int n);

}  // namespace kdrt::bench
