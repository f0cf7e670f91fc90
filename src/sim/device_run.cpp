#include "sim/device_run.hpp"

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "sim/haptic_snapshot.hpp"
#include "haptics/virtual_device.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <utility>

namespace vox::sim {
namespace {

constexpr double k_tick_s = 1e-3;
/// Surface points the snapshot can hold: a tool's neighbourhood on a fine scan is a few
/// thousand; beyond this the snapshot says it was truncated.
constexpr std::size_t k_snapshot_points = 50000;

} // namespace

haptics::CouplingSettings device_coupling(const io::ToolSpec& tool, const haptics::DeviceLimits& limits)
{
    haptics::CouplingSettings coupling;
    if (tool.coupling_stiffness_n_per_mm) coupling.stiffness_n_per_mm = *tool.coupling_stiffness_n_per_mm;
    if (limits.max_stiffness_n_per_mm > 0.0) coupling.stiffness_n_per_mm = std::min(coupling.stiffness_n_per_mm, limits.max_stiffness_n_per_mm);
    return coupling;
}

std::size_t tool_named(const io::Scene& scene, const std::string& name)
{
    if (name.empty()) return 0;
    const auto found = std::find_if(scene.tools.begin(), scene.tools.end(), [&](const io::ToolSpec& t) { return t.name == name; });
    if (found != scene.tools.end()) return static_cast<std::size_t>(found - scene.tools.begin());
    std::string names;
    for (const io::ToolSpec& t : scene.tools) names += (names.empty() ? "" : ", ") + t.name;
    throw InputError("--tool: the scene has no tool named \"" + name + "\" (it has: " + names + ")");
}

void check_device_tools(const io::Scene& scene, const std::vector<std::size_t>& tools)
{
    if (tools.size() > static_cast<std::size_t>(haptics::k_max_devices))
        throw InputError("--device: at most " + std::to_string(haptics::k_max_devices) + " devices, " + std::to_string(tools.size()) + " given");
    for (std::size_t i = 0; i < tools.size(); ++i)
        for (std::size_t j = 0; j < i; ++j)
            if (tools[i] == tools[j])
                throw InputError("--tool: tool \"" + scene.tools[tools[i]].name + "\" is driven by two devices; give each device its own --tool");
}

std::vector<haptics::KeyFrame> script_key_frames(const io::Scene& scene, std::size_t tool)
{
    std::vector<haptics::KeyFrame> frames;
    for (const io::ScriptEntry& e : scene.script)
        if (e.tool_index == tool) frames.push_back({e.t_s, e.position_mm, e.orientation});
    if (frames.empty()) throw scene.error("script", "the device follows the script of tool \"" + scene.tools[tool].name + "\", which has no entry");
    return frames;
}

DeviceRun::DeviceRun(const io::Scene& scene, const ToolPolicy& tools, const DeviceOptions& options) : m_scene(scene)
{
    if (scene.tools.empty()) throw scene.error("tools", "a device needs a tool to drive; the scene has none");
    if (options.replay) {
        m_replayed = haptics::read_recording(*options.replay);
        const int devices = haptics::recorded_devices(m_replayed);
        for (int d = 0; d < devices; ++d) {
            std::vector<haptics::RecordedTick> ticks = haptics::device_ticks(m_replayed, d);
            if (ticks.empty()) throw file_error(options.replay->string(), "holds no tick of device " + std::to_string(d));
            // Recordings made before several devices name no tool: the one asked for, else the first.
            const std::string& recorded = ticks.front().tool;
            const std::size_t tool = recorded.empty() ? tool_named(scene, options.tools.empty() ? std::string() : options.tools.front())
                                                      : tool_named(scene, recorded);
            add_hand(tool, std::make_unique<haptics::ReplayDevice>(std::move(ticks)), tools);
        }
    } else {
        const std::vector<std::string> names = options.tools.empty() ? std::vector<std::string>{std::string()} : options.tools;
        for (const std::string& name : names) {
            const std::size_t tool = tool_named(scene, name);
            add_hand(tool, std::make_unique<haptics::VirtualDevice>(script_key_frames(scene, tool)), tools);
        }
    }
    std::vector<std::size_t> driven;
    for (const std::unique_ptr<Hand>& hand : m_hands) driven.push_back(hand->tool);
    check_device_tools(scene, driven);
    // One loop serves every device, each through its own coupling and safety stage.
    std::vector<haptics::HapticChannel> channels;
    for (const std::unique_ptr<Hand>& owned : m_hands) {
        Hand* hand = owned.get();
        const haptics::SafetySettings safety = haptics::safety_for(hand->device->limits());
        channels.push_back({hand->device.get(),
                            [this, hand](const haptics::DeviceState& state, double& age) {
                                age = state.t_s - hand->snapshot.t_s;
                                return hand->coupled->update(state, hand->snapshot, m_tick_s);
                            },
                            safety,
                            [this, hand](const haptics::DeviceState& state) { hand->coupled->prepare(state, hand->snapshot, m_tick_s); }});
    }
    m_loop = std::make_unique<haptics::HapticLoop>(std::move(channels), 0);
}

void DeviceRun::add_hand(std::size_t tool, std::unique_ptr<haptics::Device> device, const ToolPolicy& tools)
{
    auto hand = std::make_unique<Hand>();
    hand->tool = tool;
    hand->device = std::move(device);
    hand->snapshot = contact::SurfacePoints(k_snapshot_points);
    const io::ToolSpec& spec = m_scene.tools[tool];
    const haptics::CouplingSettings coupling = device_coupling(spec, hand->device->limits());
    hand->coupled = std::make_unique<haptics::CoupledTool>(tools.shape(tool), contact::ContactParameters{spec.push_margin_mm, spec.contact_stiffness_n_per_mm},
                                                           coupling, hand->snapshot.capacity());
    m_hands.push_back(std::move(hand));
}

void DeviceRun::frame(Method& method, ToolPolicy& tools, double t0_s, double dt_s)
{
    if (!m_started) { // each proxy starts at its device; the readings are recorded so a replay starts alike
        for (std::size_t i = 0; i < m_hands.size(); ++i) {
            Hand& hand = *m_hands[i];
            haptics::DeviceState first;
            hand.device->read(t0_s, first);
            hand.coupled->update(first, hand.snapshot, k_tick_s);
            m_recording.push_back({first, Eigen::Vector3d::Zero(), method.level(), {}, static_cast<int>(i), m_scene.tools[hand.tool].name});
        }
        m_started = true;
    }
    // The snapshots: the surface around where each tool is, as the simulation has it at the frame's start.
    for (const std::unique_ptr<Hand>& hand : m_hands) {
        const io::ToolSpec& spec = m_scene.tools[hand->tool];
        const contact::PlacedShape pose = hand->coupled->handed_pose(); // where the simulation has the tool
        take_snapshot(method, hand->tool, spec, pose, pose.world_bounds(spec.push_margin_mm + k_snapshot_margin_mm), t0_s, hand->snapshot);
        if (hand->snapshot.truncated && !hand->warned_truncated) {
            log::warn("the surface near tool \"{}\" has more than {} points; the haptic snapshot keeps the first ones", spec.name,
                      hand->snapshot.capacity());
            hand->warned_truncated = true;
        }
    }
    for (const std::unique_ptr<Hand>& hand : m_hands) {
        hand->patch_us_max = 0.0;
        hand->coupled->set_passing(tools.passing(hand->tool)); // a tool that cut last frame cuts on through
    }
    const int ticks = std::max(1, static_cast<int>(std::lround(dt_s / k_tick_s)));
    m_tick_s = dt_s / ticks;
    for (int k = 1; k <= ticks; ++k) {
        const double t = t0_s + k * dt_s / ticks;
        m_loop->tick(t);
        const std::string change = std::exchange(m_level_change, {});
        for (std::size_t i = 0; i < m_hands.size(); ++i) {
            Hand& hand = *m_hands[i];
            const Eigen::Vector3d& f = m_loop->force(i);
            m_recording.push_back({m_loop->state(i), f, method.level(), change, static_cast<int>(i), m_scene.tools[hand.tool].name});
            hand.forces.push_back({t, hand.coupled->proxy().position, f});
            hand.patch_us_max = std::max(hand.patch_us_max, hand.coupled->patch_us());
        }
    }
    for (const std::unique_ptr<Hand>& hand : m_hands) {
        const contact::PlacedShape pose = hand->coupled->handed_pose();
        tools.drive(hand->tool, pose.position, pose.orientation, hand->coupled->driver(), hand->coupled->coupling_stiffness_n_per_mm());
    }
}

std::vector<PatchFrame> DeviceRun::patches() const
{
    std::vector<PatchFrame> out;
    for (const std::unique_ptr<Hand>& hand : m_hands) {
        const contact::PatchLayer& patch = hand->snapshot.patch;
        PatchFrame p;
        p.tool = m_scene.tools[hand->tool].name;
        p.asked = m_scene.tools[hand->tool].haptic_subdivision >= 0;
        p.touching = hand->coupled->contact().area_mm2 > 0.0;
        if (patch.free > 0) {
            p.points = patch.free;
            p.level = patch.level;
            p.compliance_mm_per_n = patch.compliance_mm_per_n;
            p.displacement_mm = hand->coupled->patch().max_displacement_mm();
            p.step_us_max = hand->patch_us_max;
        }
        out.push_back(p);
    }
    return out;
}

namespace {

/// The first recorded tick after `t0_s`, or null.
const haptics::RecordedTick* tick_after(const std::vector<haptics::RecordedTick>& ticks, double t0_s)
{
    const auto it = std::upper_bound(ticks.begin(), ticks.end(), t0_s + 1e-9,
                                     [](double t, const haptics::RecordedTick& tick) { return t < tick.state.t_s; });
    return it == ticks.end() ? nullptr : &*it;
}

} // namespace

std::optional<int> DeviceRun::recorded_level(double t0_s) const
{
    const haptics::RecordedTick* tick = tick_after(m_replayed, t0_s);
    if (!tick || tick->level <= 0) return std::nullopt;
    return tick->level;
}

std::string DeviceRun::recorded_reason(double t0_s) const
{
    const haptics::RecordedTick* tick = tick_after(m_replayed, t0_s);
    return tick && !tick->level_change.empty() ? tick->level_change : "the recording's level";
}

void write_forces(const std::filesystem::path& dir, const std::vector<ForceSample>& samples, const std::string& title, const std::string& name)
{
    write_atomically(dir / (name + ".csv"), [&](const std::filesystem::path& tmp) {
        std::FILE* f = std::fopen(tmp.c_str(), "w");
        if (!f) throw file_error(tmp.string(), "cannot be written");
        std::fprintf(f, "t_s,x_mm,y_mm,z_mm,fx_n,fy_n,fz_n\n");
        for (const ForceSample& s : samples)
            std::fprintf(f, "%.6f,%.6f,%.6f,%.6f,%.9g,%.9g,%.9g\n", s.t_s, s.position_mm.x(), s.position_mm.y(), s.position_mm.z(),
                         s.force_n.x(), s.force_n.y(), s.force_n.z());
        if (std::fclose(f) != 0) throw file_error(tmp.string(), "cannot be written");
    });
    // The magnitude against time, with a few labelled ticks on each axis.
    const double w = 720, h = 360, left = 60, right = 20, top = 30, bottom = 45;
    double t_max = 1e-9, f_max = 1e-9;
    for (const ForceSample& s : samples) {
        t_max = std::max(t_max, s.t_s);
        f_max = std::max(f_max, s.force_n.norm());
    }
    f_max *= 1.1;
    auto x = [&](double t) { return left + (w - left - right) * t / t_max; };
    auto y = [&](double f) { return h - bottom - (h - top - bottom) * f / f_max; };
    std::ostringstream o;
    o << "<svg xmlns='http://www.w3.org/2000/svg' width='" << w << "' height='" << h << "' font-family='sans-serif' font-size='12'>\n"
      << "<rect width='100%' height='100%' fill='white'/>\n"
      << "<text x='" << w / 2 << "' y='18' text-anchor='middle'>" << title << "</text>\n"
      << "<line x1='" << left << "' y1='" << h - bottom << "' x2='" << w - right << "' y2='" << h - bottom << "' stroke='black'/>\n"
      << "<line x1='" << left << "' y1='" << top << "' x2='" << left << "' y2='" << h - bottom << "' stroke='black'/>\n";
    for (int k = 0; k <= 5; ++k) {
        const double t = t_max * k / 5, f = f_max * k / 5;
        char label[32];
        std::snprintf(label, sizeof label, "%.2f", t);
        o << "<text x='" << x(t) << "' y='" << h - bottom + 16 << "' text-anchor='middle'>" << label << "</text>\n";
        std::snprintf(label, sizeof label, "%.3g", f);
        o << "<text x='" << left - 6 << "' y='" << y(f) + 4 << "' text-anchor='end'>" << label << "</text>\n";
    }
    o << "<text x='" << (left + w - right) / 2 << "' y='" << h - 8 << "' text-anchor='middle'>time (s)</text>\n"
      << "<text x='14' y='" << (top + h - bottom) / 2 << "' transform='rotate(-90 14 " << (top + h - bottom) / 2
      << ")' text-anchor='middle'>force (N)</text>\n<polyline fill='none' stroke='#c0392b' stroke-width='1.5' points='";
    for (const ForceSample& s : samples) o << x(s.t_s) << ',' << y(s.force_n.norm()) << ' ';
    o << "'/>\n</svg>\n";
    write_atomically(dir / (name + ".svg"), [&](const std::filesystem::path& tmp) { std::ofstream(tmp) << o.str(); });
}

} // namespace vox::sim
