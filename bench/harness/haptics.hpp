#pragma once
// voxsculpt bench haptics (see haptics.cpp).

#include "io/scene.hpp"

#include <string>

namespace vox::bench {

struct HapticsBenchOptions {
    double seconds = 10.0;
    io::SolverType method = io::SolverType::dbg; ///< what simulates the scene
    int devices = 1;                             ///< 1: a knife; 2: a knife and a finger pressing at once
    /// No threads: the simulation and the ticks take turns in simulated time, so every run
    /// computes the same ticks (the force time then compares builds; there is no period to time).
    bool lockstep = false;
    /// The finger's `haptic_subdivision` (contact/contact_patch.hpp): -1 (off, the default of
    /// every tool) or a level 0 - 3, to time its patch.
    int finger_subdivision = -1;
    /// What holds the knife: "script" (a scripted device pressing it, the default), or a
    /// force-feedback device, "openhaptics" or "forcedimension" (docs/devices.md), its centre
    /// placed where the script starts. Not with lockstep.
    std::string device = "script";
};

/// Runs the 1 kHz loop beside the press-and-cut simulation and prints its timing table.
void run_haptics_bench(const HapticsBenchOptions& options);

} // namespace vox::bench
