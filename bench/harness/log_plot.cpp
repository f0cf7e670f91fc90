#include "bench/harness/log_plot.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace vox::bench {

std::string log_log_plot(const std::vector<PlotSeries>& series, const std::string& x_title, const std::string& y_title)
{
    const double w = 640, h = 420, left = 70, bottom = 50, top = 20, right = 20;
    double x0 = 1e300, x1 = 0, y0 = 1e300, y1 = 0;
    for (const PlotSeries& s : series)
        for (const PlotPoint& p : s.points) {
            if (p.x <= 0 || p.y <= 0) continue;
            x0 = std::min(x0, p.x), x1 = std::max(x1, p.x);
            y0 = std::min(y0, p.y), y1 = std::max(y1, p.y);
        }
    if (x1 <= 0) x0 = y0 = 1, x1 = y1 = 10; // nothing to plot: empty axes
    x0 = std::pow(10, std::floor(std::log10(x0))), x1 = std::pow(10, std::ceil(std::log10(x1)));
    y0 = std::pow(10, std::floor(std::log10(y0))), y1 = std::pow(10, std::ceil(std::log10(y1)));
    if (x1 <= x0) x1 = 10 * x0;
    if (y1 <= y0) y1 = 10 * y0;
    auto px = [&](double x) { return left + (w - left - right) * std::log10(x / x0) / std::log10(x1 / x0); };
    auto py = [&](double y) { return h - bottom - (h - bottom - top) * std::log10(y / y0) / std::log10(y1 / y0); };
    std::ostringstream o;
    o << "<svg xmlns='http://www.w3.org/2000/svg' width='" << w << "' height='" << h
      << "' font-family='sans-serif' font-size='12'>\n<rect width='100%' height='100%' fill='white'/>\n";
    for (double x = x0; x <= x1 * 1.001; x *= 10)
        o << "<line x1='" << px(x) << "' y1='" << top << "' x2='" << px(x) << "' y2='" << h - bottom
          << "' stroke='#ddd'/><text x='" << px(x) << "' y='" << h - bottom + 16 << "' text-anchor='middle'>" << x << "</text>\n";
    for (double y = y0; y <= y1 * 1.001; y *= 10)
        o << "<line x1='" << left << "' y1='" << py(y) << "' x2='" << w - right << "' y2='" << py(y)
          << "' stroke='#ddd'/><text x='" << left - 6 << "' y='" << py(y) + 4 << "' text-anchor='end'>" << y << "</text>\n";
    o << "<text x='" << (left + w - right) / 2 << "' y='" << h - 12 << "' text-anchor='middle'>" << x_title << "</text>\n"
      << "<text transform='translate(16," << (top + h - bottom) / 2 << ") rotate(-90)' text-anchor='middle'>" << y_title << "</text>\n";
    const char* colours[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b"};
    for (std::size_t s = 0; s < series.size(); ++s) {
        const char* colour = colours[s % std::size(colours)];
        std::string path;
        for (const PlotPoint& p : series[s].points) {
            if (p.x <= 0 || p.y <= 0) continue;
            const double x = px(p.x), y = py(p.y);
            path += (path.empty() ? "M" : " L") + std::to_string(x) + " " + std::to_string(y);
            o << "<circle cx='" << x << "' cy='" << y << "' r='4' fill='" << colour << "'/><text x='" << x + 6 << "' y='" << y - 6
              << "' fill='" << colour << "'>" << p.label << "</text>\n";
        }
        if (series[s].joined) o << "<path d='" << path << "' fill='none' stroke='" << colour << "'/>\n";
        o << "<text x='" << w - right - 190 << "' y='" << top + 16 + 16 * s << "' fill='" << colour << "'>" << series[s].name << "</text>\n";
    }
    o << "</svg>\n";
    return o.str();
}

} // namespace vox::bench
