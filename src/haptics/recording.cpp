#include "haptics/recording.hpp"

#include "core/atomic_file.hpp"
#include "core/error.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

namespace vox::haptics {
namespace {

constexpr const char* k_header_v1 = "t_s,x_mm,y_mm,z_mm,qw,qx,qy,qz,buttons,fx_n,fy_n,fz_n";
constexpr const char* k_header = "t_s,x_mm,y_mm,z_mm,qw,qx,qy,qz,buttons,fx_n,fy_n,fz_n,level,level_change";

/// A reason as one CSV field: no commas, no line breaks.
std::string field_text(std::string text)
{
    for (char& c : text)
        if (c == ',' || c == '\n' || c == '\r') c = ';';
    return text;
}

} // namespace

void write_recording(const std::filesystem::path& path, const std::vector<RecordedTick>& ticks)
{
    write_atomically(path, [&](const std::filesystem::path& tmp) {
        std::FILE* f = std::fopen(tmp.c_str(), "w");
        if (!f) throw file_error(tmp.string(), "cannot be written");
        std::fprintf(f, "%s\n", k_header);
        for (const RecordedTick& t : ticks) {
            const auto& s = t.state;
            std::fprintf(f, "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%u,%.17g,%.17g,%.17g,%d,%s\n", s.t_s, s.position_mm.x(),
                         s.position_mm.y(), s.position_mm.z(), s.orientation.w(), s.orientation.x(), s.orientation.y(),
                         s.orientation.z(), static_cast<unsigned>(s.buttons), t.force_n.x(), t.force_n.y(), t.force_n.z(), t.level,
                         field_text(t.level_change).c_str());
        }
        if (std::fclose(f) != 0) throw file_error(tmp.string(), "could not be written completely");
    });
}

std::vector<RecordedTick> read_recording(const std::filesystem::path& path)
{
    const std::string name = path.string();
    if (!std::filesystem::is_regular_file(path)) throw file_error(name, std::filesystem::exists(path) ? "is not a file" : "no such file");
    std::ifstream in(path);
    std::string line;
    if (!std::getline(in, line)) throw file_error(name, "is empty; a recording starts with the line " + std::string(k_header));
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line != k_header && line != k_header_v1) throw file_error(name, "line 1: expected the header " + std::string(k_header));
    const bool levels = line == k_header; // older recordings have no level columns
    const std::size_t expected = levels ? 14 : 12;
    std::vector<RecordedTick> ticks;
    for (std::size_t row = 2; std::getline(in, line); ++row) {
        if (!line.empty() && line.back() == '\r') line.pop_back();
        const std::size_t fields = static_cast<std::size_t>(std::count(line.begin(), line.end(), ',')) + 1;
        if (fields != expected)
            throw file_error(name, "line " + std::to_string(row) + ": expected " + std::to_string(expected) + " comma-separated fields, got " +
                                       std::to_string(fields));
        double v[13];
        std::size_t count = 0, start = 0;
        while (count < (levels ? 13u : 12u)) {
            const std::size_t comma = line.find(',', start);
            const std::string cell = line.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
            char* end = nullptr;
            errno = 0;
            v[count] = std::strtod(cell.c_str(), &end);
            if (cell.empty() || *end != '\0' || errno == ERANGE || !std::isfinite(v[count]))
                throw file_error(name, "line " + std::to_string(row) + ": field " + std::to_string(count + 1) + " (\"" + cell +
                                           "\") is not a finite number");
            ++count;
            if (comma == std::string::npos) break;
            start = comma + 1;
        }
        RecordedTick t;
        t.state.t_s = v[0];
        t.state.position_mm = {v[1], v[2], v[3]};
        t.state.orientation = Eigen::Quaterniond(v[4], v[5], v[6], v[7]);
        if (std::abs(t.state.orientation.norm() - 1.0) > 1e-6)
            throw file_error(name, "line " + std::to_string(row) + ": the orientation is not a unit quaternion");
        if (v[8] < 0 || v[8] != std::floor(v[8]) || v[8] > 4294967295.0)
            throw file_error(name, "line " + std::to_string(row) + ": buttons must be a whole number bit mask");
        t.state.buttons = static_cast<std::uint32_t>(v[8]);
        t.force_n = {v[9], v[10], v[11]};
        if (levels) {
            if (v[12] < 0 || v[12] != std::floor(v[12]) || v[12] > 64)
                throw file_error(name, "line " + std::to_string(row) + ": level must be a whole number from 0 to 64");
            t.level = static_cast<int>(v[12]);
            t.level_change = line.substr(line.rfind(',') + 1);
        }
        if (!ticks.empty() && t.state.t_s < ticks.back().state.t_s)
            throw file_error(name, "line " + std::to_string(row) + ": time goes backwards");
        ticks.push_back(t);
    }
    if (ticks.empty()) throw file_error(name, "holds no tick after its header");
    return ticks;
}

ReplayDevice::ReplayDevice(std::vector<RecordedTick> ticks) : m_ticks(std::move(ticks))
{
    if (m_ticks.empty()) throw InputError("replay device: the recording holds no tick");
    m_limits.workspace_min_mm = m_limits.workspace_max_mm = m_ticks.front().state.position_mm;
    for (const RecordedTick& t : m_ticks) {
        m_limits.workspace_min_mm = m_limits.workspace_min_mm.cwiseMin(t.state.position_mm);
        m_limits.workspace_max_mm = m_limits.workspace_max_mm.cwiseMax(t.state.position_mm);
    }
}

bool ReplayDevice::read(double t_s, DeviceState& state) noexcept
{
    if (m_cursor >= m_ticks.size() || m_ticks[m_cursor].state.t_s > t_s) m_cursor = 0;
    while (m_cursor + 1 < m_ticks.size() && m_ticks[m_cursor + 1].state.t_s <= t_s) ++m_cursor;
    state = m_ticks[m_cursor].state;
    return true;
}

} // namespace vox::haptics
