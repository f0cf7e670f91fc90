#pragma once
// What the three threads of a viewer session share, and nothing else: triple buffers (the newest
// complete value, no lock) for each device's hand, the surface near its tool (simulation ->
// haptics) and its proxy's pose (haptics -> simulation); the picture (simulation -> window); the
// simulation's time (for scripted devices); and the requests the window queues for the simulation
// thread as atomics it takes once each.

#include "contact/surface_points.hpp"
#include "contact/tool_shape.hpp"
#include "haptics/triple_buffer.hpp"
#include "render/renderer.hpp"

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace vox::view {

/// What the simulation thread shows the window.
struct RenderState {
    std::vector<render::DrawMesh> meshes; ///< the surface first, then the tools (and the cage)
    double t_s = 0.0;
    std::string model;                    ///< "442 elements, level 3", or per level on two levels
    std::string tool;                     ///< the active tool and what it does
    std::string notice;                   ///< a line the window shows until it is empty again (the resume offer)
    int smooth = 0;                       ///< display smoothing the window is to give the surface
};

/// The tool the haptic thread moved, where, and where the device is heading (the surface
/// snapshot must reach that far).
struct ProxyPose {
    int tool = 0;
    contact::PlacedShape pose;
    Eigen::Vector3d heading = Eigen::Vector3d::Zero(); ///< the driver: the device, or the pointer's target
    double coupling_n_per_mm = 0.0;                     ///< the spring between them
    std::uint32_t buttons = 0;                          ///< the device's, as read
};

/// The window's requests to the simulation thread (the keys), each taken once by it.
struct ViewRequests {
    std::atomic<bool> stop{false}, paused{false}, step_once{false};
    std::atomic<bool> show_cage{false}, show_voxels{false};
    std::atomic<bool> save_object{false}, undo{false}, toggle_cut_mode{false};
    /// A stroke begins (the mouse button went down): the state before it is kept for undo.
    std::atomic<bool> stroke_started{false};
    /// The stroke ends (the button went up): its cuts go to the session journal.
    std::atomic<bool> stroke_ended{false};
    /// Resume the earlier session the journal offered (J).
    std::atomic<bool> resume{false};
    std::atomic<bool> picture_taken{true}; ///< the window has the last picture: make the next
    /// The tool the keys act on; with one device, also the tool it drives (TAB moves it).
    std::atomic<int> active{0};
    std::atomic<int> level_change{0};      ///< +1 coarser, -1 finer
    std::atomic<int> set_action{-1};       ///< 0 push, 1 cut, 2 wet for the active tool
    std::atomic<std::uint64_t> ticks{0}, frames{0}; ///< counts for the rates the window shows
};

/// One device's exchange with the simulation.
struct HandChannel {
    explicit HandChannel(std::size_t snapshot_capacity) : snapshots(contact::SurfacePoints(snapshot_capacity)) {}
    haptics::TripleBuffer<contact::SurfacePoints> snapshots;
    haptics::TripleBuffer<ProxyPose> proxies;
    /// The simulation cuts through what this hand's tool touches (sim::ToolPolicy::passing).
    std::atomic<bool> passing{false};
};

struct ViewChannels {
    /// `devices`: hands, one per device the haptic loop serves.
    explicit ViewChannels(std::size_t snapshot_capacity, std::size_t devices = 1)
    {
        for (std::size_t d = 0; d < devices; ++d) hands.push_back(std::make_unique<HandChannel>(snapshot_capacity));
    }
    [[nodiscard]] HandChannel& hand(std::size_t d = 0) { return *hands[d]; }
    std::vector<std::unique_ptr<HandChannel>> hands;
    /// The simulated time of the last frame: scripted devices follow it (haptics/paced_device.hpp).
    std::atomic<double> simulation_t_s{0.0};
    haptics::TripleBuffer<RenderState> pictures;
    ViewRequests requests;
};

} // namespace vox::view
