// Error against time: a log-log scatter plot with one panel per scene, each
// point a setting, the Pareto front (nothing both faster and more accurate)
// joined by a line. Drawn with OpenImageIO like chart.h's bar chart.
#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <vector>

namespace kdrt::bench {

struct ScatterPoint {
    std::string label;
    double x = 0.0, y = 0.0;  // time (ms), error (RMSE); y <= 0 is drawn on the floor of the axis
    bool pareto = false;
    std::array<float, 3> color{0.2f, 0.4f, 0.8f};
};

struct ScatterPanel {
    std::string title;
    std::vector<ScatterPoint> points;
};

struct ScatterPlot {
    std::string title;
    std::vector<std::string> subtitle;
    std::string x_label, y_label;
    std::vector<ScatterPanel> panels;
};

// Writes the plot as PNG; returns true when text could be drawn too.
bool draw_scatter_plot(const std::filesystem::path& path, const ScatterPlot& plot);

}  // namespace kdrt::bench
