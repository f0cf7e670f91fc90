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
constexpr const char* k_header_v2 = "t_s,x_mm,y_mm,z_mm,qw,qx,qy,qz,buttons,fx_n,fy_n,fz_n,level,level_change";
constexpr const char* k_header = "t_s,x_mm,y_mm,z_mm,qw,qx,qy,qz,buttons,fx_n,fy_n,fz_n,level,level_change,device,tool";

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
            std::fprintf(f, "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%u,%.17g,%.17g,%.17g,%d,%s,%d,%s\n", s.t_s, s.position_mm.x(),
                         s.position_mm.y(), s.position_mm.z(), s.orientation.w(), s.orientation.x(), s.orientation.y(),
                         s.orientation.z(), static_cast<unsigned>(s.buttons), t.force_n.x(), t.force_n.y(), t.force_n.z(), t.level,
                         field_text(t.level_change).c_str(), t.device, field_text(t.tool).c_str());
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
    if (line != k_header && line != k_header_v2 && line != k_header_v1)
        throw file_error(name, "line 1: expected the header " + std::string(k_header));
    // Older recordings have no level columns (v1), or no device columns (v2).
    const bool levels = line != k_header_v1, devices = line == k_header;
    const std::size_t expected = devices ? 16 : levels ? 14 : 12;
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
            // The text fields after the numbers: level_change, then device and tool.
            std::size_t at = 0;
            for (int k = 0; k < 13; ++k) at = line.find(',', at) + 1;
            const std::size_t end = line.find(',', at);
            t.level_change = line.substr(at, end == std::string::npos ? std::string::npos : end - at);
            if (devices) {
                const std::size_t tool_at = line.find(',', end + 1);
                const std::string cell = line.substr(end + 1, tool_at - end - 1);
                char* stop = nullptr;
                const long d = std::strtol(cell.c_str(), &stop, 10);
                if (cell.empty() || *stop != '\0' || d < 0 || d >= k_max_devices)
                    throw file_error(name, "line " + std::to_string(row) + ": device (\"" + cell + "\") must be a whole number from 0 to " +
                                               std::to_string(k_max_devices - 1));
                t.device = static_cast<int>(d);
                t.tool = line.substr(tool_at + 1);
            }
        }
        if (!ticks.empty() && t.state.t_s < ticks.back().state.t_s)
            throw file_error(name, "line " + std::to_string(row) + ": time goes backwards");
        ticks.push_back(t);
    }
    if (ticks.empty()) throw file_error(name, "holds no tick after its header");
    return ticks;
}

int recorded_devices(const std::vector<RecordedTick>& ticks)
{
    int n = 0;
    for (const RecordedTick& t : ticks) n = std::max(n, t.device + 1);
    return n;
}

std::vector<RecordedTick> device_ticks(const std::vector<RecordedTick>& ticks, int device)
{
    std::vector<RecordedTick> out;
    for (const RecordedTick& t : ticks)
        if (t.device == device) out.push_back(t);
    return out;
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
