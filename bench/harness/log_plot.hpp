#pragma once
// A log-log scatter plot as SVG, for the benches' speed-against-accuracy figures: points (joined
// per series where they form a sequence), each labelled, a legend; points at or below zero on either axis are left out (a
// reference has no error of its own).

#include <string>
#include <vector>

namespace vox::bench {

struct PlotPoint {
    double x = 0.0, y = 0.0;
    std::string label;
};
struct PlotSeries {
    std::string name;
    std::vector<PlotPoint> points;
    bool joined = true; ///< a line through the points in order (a sequence, such as levels); else points only
};

[[nodiscard]] std::string log_log_plot(const std::vector<PlotSeries>& series, const std::string& x_title, const std::string& y_title);

} // namespace vox::bench
