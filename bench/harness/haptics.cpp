// voxsculpt bench haptics: how steady the 1 kHz loop is, and how long its force takes, while a
// cutting simulation runs beside it. The threads are those of a live session:
//  - the haptic thread (its own, 1 kHz on absolute deadlines) serves every device: a scripted
//    device pressing a knife into the block of data/scenes/press_and_cut.json again and again, a
//    little further along each time, and jabbing it in between (jumps of several mm a tick); with
//    --devices 2 a second one pressing a finger (a ball) into the block beside the knife's path at
//    the same time, out of step with it. Each device has its own virtual coupling against the
//    penalty contact with the newest surface snapshot near its tool, and its own safety stage; the
//    loop publishes the tools' poses;
//  - the simulation thread (this one) puts the tools where the haptic thread says, lets them cut
//    and push, steps the simulation (the scene's method, or another with --solver), publishes the
//    surface near each tool, and keeps simulated time in pace with wall time. The scene is
//    press_and_cut.json one level coarser, which one core steps in real time: the snapshots stay
//    fresher than the safety stage's 50 ms.
// They share only triple buffers. Prints period error, force time (from reading the first device
// to sending the last force) and the tick's whole work (the contacts the couplings prepare for the
// next tick after the forces are sent included), p50, p99 and max over every device, with the
// cutting and the snapshots' sizes.

#include "bench/harness/haptics.hpp"
#include "sim/frame_loop.hpp"
#include "sim/haptic_snapshot.hpp"
#include "sim/method_factory.hpp"
#include "core/log.hpp"
#include "core/sample_stats.hpp"
#include "haptics/coupled_tool.hpp"
#include "haptics/haptic_loop.hpp"
#include "haptics/triple_buffer.hpp"
#include "haptics/forcedimension_device.hpp"
#include "haptics/framed_device.hpp"
#include "haptics/openhaptics_device.hpp"
#include "haptics/virtual_device.hpp"
#include "io/scene_object.hpp"

#include <tbb/global_control.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <chrono>
#include <thread>
#include <cstdio>

namespace vox::bench {
namespace {

struct Percentiles {
    double p50 = 0, p99 = 0, max = 0;
};

Percentiles percentiles(const std::vector<double>& v)
{
    return {quantile(v, 0.5), quantile(v, 0.99), quantile(v, 1.0)};
}

/// The machine's own noise, to read the force times by: a fixed computation of about 20 us (a
/// heavy tick's length) timed 2,000 times. A virtual machine's interruptions land on a tick as
/// often as on it, and add to its p99 what they add here.
Percentiles machine_noise_us()
{
    using clock = std::chrono::steady_clock;
    volatile double sink = 0.0;
    auto timed = [&](int n) {
        const auto t0 = clock::now();
        double sum = 0.0;
        for (int k = 0; k < n; ++k) sum += std::sqrt(k + 0.5);
        sink = sum;
        return std::chrono::duration<double, std::micro>(clock::now() - t0).count();
    };
    std::vector<double> us;
    for (int k = 0; k < 50; ++k) us.push_back(timed(10000));
    const int n = std::max(1, static_cast<int>(10000 * 20.0 / std::max(quantile(us, 0.5), 1e-3)));
    us.clear();
    for (int k = 0; k < 2000; ++k) us.push_back(timed(n));
    return percentiles(us);
}

/// Presses into the block, one a second, each 1.5 mm further along x, starting over every 16; and
/// after each press a jab 0.75 mm beside it, 7.5 mm down in 2 ms (3.75 mm a tick: the jumps that
/// make the loop sweep the tool's mesh against the surface).
std::vector<haptics::KeyFrame> presses(double seconds)
{
    std::vector<haptics::KeyFrame> frames;
    const Eigen::Quaterniond level = Eigen::Quaterniond::Identity();
    for (int k = 0; k <= static_cast<int>(seconds) + 1; ++k) {
        const double x = 8.0 + 1.5 * (k % 16);
        frames.push_back({static_cast<double>(k), {x, 10, 17}, level});
        frames.push_back({k + 0.5, {x, 10, 9.5}, level});
        frames.push_back({k + 0.6, {x, 10, 9.5}, level});
        frames.push_back({k + 0.75, {x + 0.75, 10, 17}, level});
        frames.push_back({k + 0.8, {x + 0.75, 10, 17}, level});
        frames.push_back({k + 0.802, {x + 0.75, 10, 9.5}, level});
        frames.push_back({k + 0.85, {x + 0.75, 10, 9.5}, level});
        frames.push_back({k + 0.99, {x, 10, 17}, level});
    }
    return frames;
}

/// The second hand: a ball of 4 mm pressing 2 mm into the block at y = 16 (clear of the knife
/// at y = 10), half a second out of step with the knife, from the far end of the block inwards.
std::vector<haptics::KeyFrame> finger_presses(double seconds)
{
    std::vector<haptics::KeyFrame> frames;
    const Eigen::Quaterniond level = Eigen::Quaterniond::Identity();
    for (int k = 0; k <= static_cast<int>(seconds) + 1; ++k) {
        const double x = 32.0 - 1.5 * (k % 16);
        frames.push_back({static_cast<double>(k), {x, 16, 20}, level});
        frames.push_back({k + 0.3, {x, 16, 20}, level});
        frames.push_back({k + 0.8, {x, 16, 14}, level});
        frames.push_back({k + 0.95, {x, 16, 14}, level});
    }
    return frames;
}

/// Where the loop put a tool (its proxy) and its device (the driver).
struct HandPose {
    contact::PlacedShape proxy;
    Eigen::Vector3d driver = Eigen::Vector3d::Zero();
};

/// One device and its tool: the haptic thread's side (device, coupling) and what the threads share.
struct Hand {
    std::size_t tool = 0;
    std::unique_ptr<haptics::Device> vendor; ///< a force-feedback device the hand holds instead of a script (--device)
    std::unique_ptr<haptics::Device> device; ///< what the loop reads: the script, or the vendor's device placed in the scene
    haptics::CoupledTool coupled;
    haptics::TripleBuffer<contact::SurfacePoints> snapshots; ///< simulation -> haptics
    haptics::TripleBuffer<HandPose> poses;                   ///< haptics -> simulation
    HandPose pose;                                           ///< simulation side: the last pose read
    std::atomic<bool> passing{false};                        ///< simulation -> haptics: the tool cuts through
    Hand(std::size_t t, std::vector<haptics::KeyFrame> frames, const contact::ToolShape& shape, const io::ToolSpec& spec, std::size_t capacity)
        : tool(t), device(std::make_unique<haptics::VirtualDevice>(std::move(frames))),
          coupled(shape, contact::ContactParameters{spec.push_margin_mm, spec.contact_stiffness_n_per_mm}, haptics::CouplingSettings{}, capacity),
          snapshots(contact::SurfacePoints(capacity))
    {
    }
};

} // namespace

void run_haptics_bench(const HapticsBenchOptions& options)
{
    const double seconds = options.seconds;
    const io::SolverType method_type = options.method;
    const int devices = options.devices;
    const bool lockstep = options.lockstep;
    // The press-and-cut scene one level coarser (2 mm -> 4 mm elements), so that the simulation
    // thread alone keeps its snapshots fresh (under the 50 ms the safety stage allows).
    io::Scene scene = io::load_scene(VOX_DATA_DIR "/scenes/press_and_cut.json");
    scene.object.levels = 2;
    if (devices > 1) { // the second hand's tool
        io::ToolSpec finger;
        finger.name = "finger";
        finger.shape = io::ToolShape::sphere;
        finger.radius_mm = 4.0;
        finger.action = io::default_tool_action(io::ToolShape::sphere);
        finger.haptic_subdivision = options.finger_subdivision;
        scene.tools.push_back(finger);
    }
    io::use_method(scene, method_type);
    constexpr std::size_t snapshot_capacity = 50000;
    const std::unique_ptr<sim::Method> method =
        sim::open_method(scene, std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene))).method;
    sim::ToolPolicy tools(scene);
    sim::FrameLoop frame_loop(scene, *method, tools);
    std::vector<std::unique_ptr<Hand>> hands;
    hands.push_back(std::make_unique<Hand>(0, presses(seconds), tools.shape(0), scene.tools[0], snapshot_capacity));
    if (options.device != "script") { // the knife in the hand on a force-feedback device, its centre where the script starts
        Hand& knife = *hands.front();
        if (options.device == "openhaptics") knife.vendor = std::make_unique<haptics::OpenHapticsDevice>();
        else knife.vendor = std::make_unique<haptics::ForceDimensionDevice>();
        haptics::DeviceState start;
        knife.device->read(0.0, start);
        knife.device = std::make_unique<haptics::FramedDevice>(*knife.vendor, haptics::DeviceFrame{start.position_mm, start.orientation, 1.0});
    }
    if (devices > 1) hands.push_back(std::make_unique<Hand>(1, finger_presses(seconds), tools.shape(1), scene.tools[1], snapshot_capacity));

    using clock = std::chrono::steady_clock;
    const auto start = clock::now();
    // Lockstep: simulated time, the ticks run by this thread between frames (the same ticks every run).
    double simulated_s = 0.0;
    auto now_s = [&] { return lockstep ? simulated_s : std::chrono::duration<double>(clock::now() - start).count(); };
    // The simulation keeps to one thread: the other core is the loop's.
    const tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
    // Written by the haptic thread only (sized here), read after it has stopped. The knife's mesh
    // sweeps are counted per tick.
    std::size_t stale_ticks = 0, prepared_ticks = 0, tick = 0;
    const std::size_t capacity = static_cast<std::size_t>(seconds * 1000) + 1000;
    std::vector<unsigned char> swept_mesh(capacity, 0), stopped_by_mesh(capacity, 0); // per tick
    // Per tick, the time the contact patches took (contact/contact_patch.hpp), all devices.
    std::vector<double> patch_us(capacity, 0.0);
    const double stale_s = haptics::SafetySettings{}.stale_s;
    std::vector<haptics::HapticChannel> channels;
    for (std::size_t i = 0; i < hands.size(); ++i) {
        Hand* hand = hands[i].get();
        const bool knife = i == 0;
        channels.push_back({hand->device.get(),
                            [&, hand, knife](const haptics::DeviceState& s, double& age) -> Eigen::Vector3d {
                                // The snapshot the last tick's prepare took (and measured the contact on).
                                const contact::SurfacePoints& surface = hand->snapshots.read_slot();
                                age = now_s() - surface.t_s;
                                stale_ticks += age > stale_s;
                                hand->coupled.set_passing(hand->passing.load(std::memory_order_relaxed));
                                const Eigen::Vector3d f = hand->coupled.update(s, surface, 1e-3);
                                prepared_ticks += hand->coupled.used_prepared();
                                // The knife's channel runs first and counts the tick.
                                if (const std::size_t at = knife ? tick : tick - 1; at < capacity) patch_us[at] += hand->coupled.patch_us();
                                if (knife) {
                                    if (tick < capacity) {
                                        swept_mesh[tick] = hand->coupled.sweep().swept_mesh();
                                        stopped_by_mesh[tick] = hand->coupled.sweep().stopped_by_mesh();
                                    }
                                    ++tick;
                                }
                                hand->poses.write_slot() = {hand->coupled.handed_pose(), s.position_mm};
                                hand->poses.publish();
                                return f;
                            },
                            haptics::safety_for(hand->device->limits()),
                            [hand](const haptics::DeviceState& s) { hand->coupled.prepare(s, hand->snapshots.latest(), 1e-3); }});
    }
    haptics::HapticLoop loop(std::move(channels), capacity);

    log::info("bench haptics: 1 kHz loop for {} s, {} device(s) (the knife's: {}), against a cutting simulation ({}, {}){}", seconds, hands.size(),
              hands.front()->device->name(), scene.source, io::solver_type_name(method_type), lockstep ? ", lockstep" : "");
    if (!lockstep) loop.start();
    std::vector<double> lockstep_force_us, lockstep_work_us;
    int frames = 0, cutting_frames = 0;
    std::vector<double> snapshot_points, frame_ms;
    for (const std::unique_ptr<Hand>& hand : hands) { // the devices' first poses, until the loop reports
        hand->pose.proxy = hand->coupled.proxy();
        haptics::DeviceState first;
        hand->device->read(0.0, first);
        hand->pose.proxy.position = hand->pose.driver = first.position_mm;
    }
    while (lockstep ? frames * scene.solver.dt_s < seconds : now_s() < seconds) {
        const auto frame_start = clock::now();
        for (const std::unique_ptr<Hand>& hand : hands) {
            if (hand->poses.update()) hand->pose = hand->poses.read_slot();
            tools.drive(hand->tool, hand->pose.proxy.position, hand->pose.proxy.orientation, hand->pose.driver,
                        hand->coupled.coupling_stiffness_n_per_mm());
        }
        const sim::FrameStats f = frame_loop.next();
        for (const std::unique_ptr<Hand>& hand : hands) hand->passing.store(tools.passing(hand->tool), std::memory_order_relaxed);
        cutting_frames += f.tools.cut.changed();
        double points = 0.0;
        for (const std::unique_ptr<Hand>& hand : hands) {
            const io::ToolSpec& spec = scene.tools[hand->tool];
            contact::SurfacePoints& out = hand->snapshots.write_slot();
            sim::take_snapshot(*method, hand->tool, spec, hand->pose.proxy, hand->pose.proxy.world_bounds(spec.push_margin_mm + sim::k_snapshot_margin_mm), now_s(), out);
            hand->snapshots.publish();
            points += static_cast<double>(out.count);
        }
        snapshot_points.push_back(points);
        frame_ms.push_back(std::chrono::duration<double, std::milli>(clock::now() - frame_start).count());
        ++frames;
        if (lockstep) { // the frame's ticks, timed one by one
            const int ticks_per_frame = static_cast<int>(std::lround(scene.solver.dt_s / 1e-3));
            for (int k = 1; k <= ticks_per_frame; ++k) {
                simulated_s = (frames - 1) * scene.solver.dt_s + k * 1e-3;
                loop.tick(simulated_s);
                lockstep_force_us.push_back(loop.last_force_us());
                lockstep_work_us.push_back(loop.last_work_us());
            }
            continue;
        }
        // Simulated time keeps pace with wall time, as in a live session (a late frame does not wait).
        std::this_thread::sleep_until(start + std::chrono::duration<double>(frames * scene.solver.dt_s));
    }
    loop.stop();
    const Percentiles period = percentiles(lockstep ? std::vector<double>{0.0} : loop.timings().period_error_ms);
    const std::vector<double>& force_us = lockstep ? lockstep_force_us : loop.timings().force_us;
    const Percentiles force = percentiles(force_us);
    const Percentiles work = percentiles(lockstep ? lockstep_work_us : loop.timings().work_us);
    // The ticks that swept the knife's mesh (the costliest kind), on their own.
    std::vector<double> mesh_force_us;
    std::size_t mesh_stops = 0;
    for (std::size_t i = 0; i < force_us.size() && i < capacity; ++i)
        if (swept_mesh[i]) {
            mesh_force_us.push_back(force_us[i]);
            mesh_stops += stopped_by_mesh[i];
        }
    const Percentiles mesh_force = percentiles(mesh_force_us);
    // The ticks that stepped a contact patch, on their own.
    std::vector<double> patch_ticks_us;
    for (std::size_t i = 0; i < std::min(tick, capacity); ++i)
        if (patch_us[i] > 0.0) patch_ticks_us.push_back(patch_us[i]);
    const Percentiles patch = percentiles(patch_ticks_us.empty() ? std::vector<double>{0.0} : patch_ticks_us);
    const Percentiles noise = machine_noise_us();
    std::printf("machine: %s; its noise, a fixed computation timed 2,000 times: p50 %.1f / p99 %.1f / max %.1f us\n\n",
                machine_description().c_str(), noise.p50, noise.p99, noise.max);
    const std::size_t ticks = force_us.size();
    std::printf("| ticks | simulation frames (median) | cutting frames | snapshot points, all devices (median) | device ticks on a stale snapshot | "
                "real-time priority | period error p50 / p99 / max | force time p50 / p99 / max | tick's work p50 / p99 / max | "
                "ticks that swept the knife's mesh (stopped by it) | their force time p50 / p99 / max | devices |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    std::printf("| %zu | %d (%.1f ms) | %d | %.0f | %.1f %% | %s | %.4f / %.4f / %.3f ms | %.1f / %.1f / %.1f us | %.1f / %.1f / %.1f us | %zu (%zu) | %.1f / %.1f / %.1f us | %zu |\n",
                ticks, frames, quantile(frame_ms, 0.5), cutting_frames, quantile(snapshot_points, 0.5),
                100.0 * static_cast<double>(stale_ticks) / static_cast<double>(std::max<std::size_t>(ticks * hands.size(), 1)),
                loop.timings().realtime_priority ? "yes" : "no (not permitted)", period.p50, period.p99, period.max, force.p50, force.p99,
                force.max, work.p50, work.p99, work.max, mesh_force_us.size(), mesh_stops, mesh_force.p50, mesh_force.p99, mesh_force.max, hands.size());
    std::printf("\ndevice ticks answered from the contact prepared after the tick before: %.1f %%\n",
                100.0 * static_cast<double>(prepared_ticks) / static_cast<double>(std::max<std::size_t>(ticks * hands.size(), 1)));
    std::printf("\ncontact patches (haptic subdivision): stepped in %zu ticks, %.1f / %.1f / %.1f us of the tick (p50 / p99 / max)\n",
                patch_ticks_us.size(), patch.p50, patch.p99, patch.max);
    std::printf("\ntargets: p99 period error under 0.1 ms (%s), p99 force time under 100 us (%s), p99 patch time under 30 us (%s)\n",
                period.p99 < 0.1 ? "met" : "not met", force.p99 < 100.0 ? "met" : "not met",
                patch_ticks_us.empty() ? "no patch" : patch.p99 < 30.0 ? "met" : "not met");
}

} // namespace vox::bench
