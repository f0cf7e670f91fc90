#pragma once
// voxsculpt bench haptics (see haptics.cpp).

#include "io/scene.hpp"

namespace vox::bench {

/// Runs the 1 kHz loop for `seconds` beside the press-and-cut simulation with `method`, serving
/// `devices` devices (1: a knife; 2: a knife and a finger pressing at once), and prints its
/// timing table. `lockstep`: no threads; the simulation and the ticks take turns in simulated
/// time, so every run computes the same ticks (the force time then compares builds; there is no
/// period to time).
void run_haptics_bench(double seconds, io::SolverType method = io::SolverType::dbg, int devices = 1, bool lockstep = false);

} // namespace vox::bench
