#include "sim/device_run.hpp"

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/sample_stats.hpp"
#include "haptics/force_devices.hpp"
#include "haptics/paced_device.hpp"
#include "io/tool_script.hpp"
#include "sim/haptic_snapshot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <utility>

namespace vox::sim {
namespace {

constexpr double k_tick_s = 1e-3;
/// Surface points the snapshot can hold: a tool's neighbourhood on a fine scan is a few
/// thousand; beyond this the snapshot says it was truncated.
constexpr std::size_t k_snapshot_points = 50000;
/// Ticks a device's ring holds between two frames: 30 s of a simulation that fell behind.
constexpr std::size_t k_ring_ticks = 30000;

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

haptics::DeviceFrame device_frame(const io::ToolSpec& tool, const Eigen::Vector3d& start_mm)
{
    if (tool.device_frame) return {tool.device_frame->origin_mm, tool.device_frame->rotation, tool.device_frame->scale};
    return {start_mm, Eigen::Quaterniond::Identity(), 1.0};
}

DeviceRun::Hand::Hand() : snapshots(contact::SurfacePoints(k_snapshot_points)), ticks(k_ring_ticks) {}

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
            add_hand(tool, std::make_unique<haptics::ReplayDevice>(std::move(ticks)), tools, false);
        }
    } else {
        const std::size_t count = std::max<std::size_t>({options.devices.size(), options.tools.size(), 1});
        const auto kind = [&](std::size_t d) { return d < options.devices.size() ? options.devices[d] : std::string("script"); };
        std::vector<std::size_t> driven;
        for (std::size_t d = 0; d < count; ++d) {
            if (kind(d) != "script" && !haptics::is_force_device(kind(d)))
                throw InputError("--device " + kind(d) + ": a run takes script, openhaptics or forcedimension");
            m_live = m_live || haptics::is_force_device(kind(d));
            driven.push_back(tool_named(scene, d < options.tools.size() ? options.tools[d] : std::string()));
        }
        check_device_tools(scene, driven); // before any device is opened
        std::map<std::string, int> opened; // force-feedback devices, per backend
        for (std::size_t d = 0; d < count; ++d) {
            const std::size_t tool = driven[d];
            if (kind(d) == "script") {
                std::vector<haptics::KeyFrame> script = script_key_frames(scene, tool);
                if (m_live) // it keeps to the simulation's time, as the run's frames keep to the wall's
                    add_hand(tool, std::make_unique<haptics::PacedDevice>(std::move(script), m_simulation_t_s, scene.solver.dt_s), tools, false);
                else
                    add_hand(tool, std::make_unique<haptics::VirtualDevice>(std::move(script)), tools, false);
                continue;
            }
            const io::ToolSpec& spec = scene.tools[tool];
            const io::ToolPose start = io::tool_pose(scene, tool, 0.0);
            if (!spec.device_frame && !start.placed)
                throw scene.error("tools", "tool \"" + spec.name + "\" is driven by a force-feedback device, whose frame the tool's \"device_frame\" "
                                           "or a script entry (its first position) places in the scene; it has neither");
            add_hand(tool, haptics::open_force_device(kind(d), opened[kind(d)]++, device_frame(spec, start.position_mm)), tools, true);
            m_hands.back()->pose.pose.position = start.placed ? start.position_mm : spec.device_frame->origin_mm;
        }
    }
    if (options.replay) {
        std::vector<std::size_t> driven;
        for (const std::unique_ptr<Hand>& hand : m_hands) driven.push_back(hand->tool);
        check_device_tools(scene, driven);
    }
    // One loop serves every device, each through its own coupling and safety stage; after each
    // tick, each leaves its reading, force and proxy for the simulation thread.
    std::vector<haptics::HapticChannel> channels;
    for (std::size_t i = 0; i < m_hands.size(); ++i) {
        Hand* hand = m_hands[i].get();
        const haptics::SafetySettings safety = haptics::safety_for(hand->device->limits());
        channels.push_back({hand->device.get(),
                            [this, hand](const haptics::DeviceState& state, double& age) {
                                const contact::SurfacePoints& surface = hand->snapshots.read_slot();
                                age = state.t_s - surface.t_s;
                                return hand->coupled->update(state, surface, m_tick_s);
                            },
                            safety,
                            [this, hand, i](const haptics::DeviceState& state) {
                                haptics::CoupledTool& coupled = *hand->coupled;
                                hand->ticks.push({m_loop->last_tick_s(), state, m_loop->force(i), coupled.proxy().position, coupled.patch_us()});
                                coupled.prepare(state, hand->snapshots.latest(), m_tick_s);
                                HandPose& out = hand->poses.write_slot();
                                out = {coupled.handed_pose(), coupled.driver(), coupled.coupling_stiffness_n_per_mm(), state.buttons,
                                       coupled.contact().area_mm2 > 0.0, coupled.patch().max_displacement_mm()};
                                hand->poses.publish();
                            }});
    }
    // A live loop keeps its timings: a tick's work and period, ten minutes of them.
    m_loop = std::make_unique<haptics::HapticLoop>(std::move(channels), m_live ? 600000 : 0);
}

DeviceRun::~DeviceRun()
{
    if (m_loop) m_loop->stop(); // before the devices and what the loop's channels refer to go
}

void DeviceRun::add_hand(std::size_t tool, std::unique_ptr<haptics::Device> device, const ToolPolicy& tools, bool arms)
{
    auto hand = std::make_unique<Hand>();
    hand->tool = tool;
    hand->device = std::move(device);
    hand->arms = arms;
    const io::ToolSpec& spec = m_scene.tools[tool];
    const haptics::CouplingSettings coupling = device_coupling(spec, hand->device->limits());
    hand->coupled = std::make_unique<haptics::CoupledTool>(tools.shape(tool), contact::ContactParameters{spec.push_margin_mm, spec.contact_stiffness_n_per_mm},
                                                           coupling, k_snapshot_points);
    hand->pose.pose = {&tools.shape(tool), Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity()};
    hand->pose.coupling_n_per_mm = coupling.stiffness_n_per_mm;
    m_hands.push_back(std::move(hand));
}

double DeviceRun::live_now_s() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - m_live_start).count(); }

void DeviceRun::start(const Method& method, double t0_s)
{
    m_started = true;
    if (m_live) { // each proxy goes to its device at the loop's first tick; until then the tool is where its frame starts
        for (const std::unique_ptr<Hand>& hand : m_hands) hand->pose.driver_mm = hand->pose.pose.position;
        return;
    }
    // Lockstep: each proxy starts at its device; the readings are recorded so a replay starts alike.
    for (std::size_t i = 0; i < m_hands.size(); ++i) {
        Hand& hand = *m_hands[i];
        haptics::DeviceState first;
        hand.device->read(t0_s, first);
        hand.coupled->update(first, hand.snapshots.read_slot(), k_tick_s);
        hand.pose = {hand.coupled->handed_pose(), hand.coupled->driver(), hand.coupled->coupling_stiffness_n_per_mm(), first.buttons, false, 0.0};
        m_recording.push_back({first, Eigen::Vector3d::Zero(), method.level(), {}, static_cast<int>(i), m_scene.tools[hand.tool].name});
    }
}

void DeviceRun::publish_snapshots(Method& method, double t_s)
{
    for (const std::unique_ptr<Hand>& hand : m_hands) {
        const io::ToolSpec& spec = m_scene.tools[hand->tool];
        const contact::PlacedShape& pose = hand->pose.pose; // where the simulation has the tool
        const double margin = spec.push_margin_mm + k_snapshot_margin_mm;
        Eigen::AlignedBox3d near = pose.world_bounds(margin);
        if (m_live) // the hand moves on while the simulation steps: the snapshot reaches to where it heads
            near.extend(contact::PlacedShape{pose.shape, hand->pose.driver_mm, pose.orientation}.world_bounds(margin));
        contact::SurfacePoints& out = hand->snapshots.write_slot();
        take_snapshot(method, hand->tool, spec, pose, near, t_s, out);
        if (out.truncated && !hand->warned_truncated) {
            log::warn("the surface near tool \"{}\" has more than {} points; the haptic snapshot keeps the first ones", spec.name, out.capacity());
            hand->warned_truncated = true;
        }
        hand->patch_points = out.patch.free;
        hand->patch_level = out.patch.level;
        hand->patch_compliance_mm_per_n = out.patch.compliance_mm_per_n;
        hand->snapshots.publish();
        if (!m_live) hand->snapshots.update(); // lockstep: the loop's ticks, on this thread, take it now
    }
}

void DeviceRun::take_ticks(const Method& method)
{
    for (const std::unique_ptr<Hand>& hand : m_hands) {
        hand->patch_us_max = 0.0;
        if (hand->poses.update()) hand->pose = hand->poses.read_slot();
    }
    // Tick by tick, every device in turn (each tick serves them all, so their rings fill alike).
    std::size_t ready = SIZE_MAX;
    for (const std::unique_ptr<Hand>& hand : m_hands) ready = std::min(ready, hand->ticks.size());
    for (std::size_t k = 0; k < ready; ++k) {
        const std::string change = std::exchange(m_level_change, {});
        for (std::size_t i = 0; i < m_hands.size(); ++i) {
            Hand& hand = *m_hands[i];
            const HandTick& t = hand.ticks.front();
            m_recording.push_back({t.state, t.force_n, method.level(), change, static_cast<int>(i), m_scene.tools[hand.tool].name});
            hand.forces.push_back({t.t_s, t.proxy_mm, t.force_n});
            hand.patch_us_max = std::max(hand.patch_us_max, t.patch_us);
            hand.ticks.pop();
        }
    }
}

void DeviceRun::watch_faults()
{
    for (const std::unique_ptr<Hand>& hand : m_hands) {
        const char* fault = hand->device->fault();
        if (fault && fault != hand->fault_said) {
            if (!hand->fault_said) ++hand->faults;
            log::warn("{} (tool \"{}\"): {}: no force, the tool held where it was; the run goes on and takes the device up again when it answers",
                      hand->device->name(), m_scene.tools[hand->tool].name, fault);
        } else if (!fault && hand->fault_said) {
            log::info("{} (tool \"{}\") answers again: its force ramps back in", hand->device->name(), m_scene.tools[hand->tool].name);
        }
        hand->fault_said = fault;
        if (fault) hand->device->recover();
    }
}

void DeviceRun::frame(Method& method, ToolPolicy& tools, double t0_s, double dt_s)
{
    if (!m_started) start(method, t0_s);
    for (const std::unique_ptr<Hand>& hand : m_hands)
        hand->coupled->set_passing(tools.passing(hand->tool)); // a tool that cut last frame cuts on through
    if (m_live) {
        m_simulation_t_s.store(t0_s, std::memory_order_relaxed);
        if (!m_loop->running()) {
            publish_snapshots(method, 0.0);
            m_live_start = std::chrono::steady_clock::now();
            m_loop->start();
        }
        take_ticks(method);
        publish_snapshots(method, live_now_s()); // around where each tool is now, for the ticks to come
    } else {
        // The surface around where each tool is, as the simulation has it at the frame's start.
        publish_snapshots(method, t0_s);
        const int ticks = std::max(1, static_cast<int>(std::lround(dt_s / k_tick_s)));
        m_tick_s = dt_s / ticks;
        for (int k = 1; k <= ticks; ++k) m_loop->tick(t0_s + k * dt_s / ticks);
        take_ticks(method);
    }
    watch_faults();
    for (const std::unique_ptr<Hand>& hand : m_hands) {
        const HandPose& p = hand->pose;
        tools.drive(hand->tool, p.pose.position, p.pose.orientation, p.driver_mm, p.coupling_n_per_mm);
        if (hand->arms) tools.arm(hand->tool, (p.buttons & haptics::k_action_button) != 0);
    }
}

void DeviceRun::finish(const Method& method)
{
    if (!m_live) return;
    m_loop->stop();
    take_ticks(method);
    for (const std::unique_ptr<Hand>& hand : m_hands)
        if (const std::uint64_t dropped = hand->ticks.dropped())
            log::warn("{}: {} ticks were not recorded (the simulation fell behind the loop by more than {} s)", hand->device->name(), dropped,
                      k_ring_ticks / 1000);
}

nlohmann::json DeviceRun::loop_figures() const
{
    const haptics::LoopTimings& t = m_loop->timings();
    const double seconds = m_hands.empty() || m_hands.front()->forces.empty() ? 0.0 : m_hands.front()->forces.back().t_s;
    return {{"ticks", t.force_us.size()},
            {"rate_hz", seconds > 0.0 ? static_cast<double>(t.force_us.size()) / seconds : 0.0},
            {"period_error_ms_p50", quantile(t.period_error_ms, 0.5)},
            {"period_error_ms_p99", quantile(t.period_error_ms, 0.99)},
            {"force_us_p50", quantile(t.force_us, 0.5)},
            {"force_us_p99", quantile(t.force_us, 0.99)},
            {"realtime_priority", t.realtime_priority}};
}

std::vector<PatchFrame> DeviceRun::patches() const
{
    std::vector<PatchFrame> out;
    for (const std::unique_ptr<Hand>& hand : m_hands) {
        PatchFrame p;
        p.tool = m_scene.tools[hand->tool].name;
        p.asked = m_scene.tools[hand->tool].haptic_subdivision >= 0;
        p.touching = hand->pose.touching;
        if (hand->patch_points > 0) {
            p.points = hand->patch_points;
            p.level = hand->patch_level;
            p.compliance_mm_per_n = hand->patch_compliance_mm_per_n;
            p.displacement_mm = hand->pose.patch_displacement_mm;
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
