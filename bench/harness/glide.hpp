#pragma once
// voxsculpt bench glide: how smooth the force a device feels is while its tool glides across the
// surface, pressed in at a constant depth, crossing particles (surface points, nodes, clusters)
// as it goes: a ball of 3 mm radius pressed 1 mm into a block (E = 20 kPa, level 1, held at its
// base) and drawn 24 mm across it, twelve elements, through the device path at 1 kHz (lockstep),
// for each method, at two speeds. The figure is the change of the force from one tick to the
// next. No force-output device is attached to the machine this is measured on: the number stands
// for what a hand would feel. Shape matching's force is its constraint particle coupling
// (docs/shape-matching.md), the finite-element methods' the penalty contact.

#include "io/scene.hpp"

#include <filesystem>
#include <vector>

namespace vox::bench {

struct GlideFigures {
    io::SolverType method = io::SolverType::dbg;
    double speed_mm_s = 0.0;
    double mean_force_n = 0.0;       ///< while gliding
    double largest_change_n = 0.0;   ///< from one tick to the next, while gliding
    double p99_change_n = 0.0;
    double median_change_n = 0.0;
    std::size_t ticks = 0;           ///< gliding
};

/// One glide at `speed_mm_s` with `method`.
[[nodiscard]] GlideFigures glide(io::SolverType method, double speed_mm_s = 20.0);

/// Every method at 20 and 60 mm/s; writes DIR/glide.md and DIR/glide.json.
void run_glide_bench(const std::filesystem::path& dir);

} // namespace vox::bench
