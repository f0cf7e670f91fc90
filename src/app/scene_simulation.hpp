#pragma once
// A scene made ready to simulate at one level: the mechanical model, the solver with the scene's
// constraints, loads, gravity, materials (plasticity, wetting) and wet regions, its
// preconditioner, and the surface it moves. `voxsculpt run`, the level choice and the benchmarks
// all build their simulations here, so they simulate the same thing.

#include "app/model_surface.hpp"
#include "fem/implicit_solver.hpp"
#include "io/scene.hpp"
#include "io/scene_object.hpp"

#include <memory>
#include <string>

namespace vox::app {

/// The grid of a scene's object, with levels up to `max_level` (coarser levels than the simulated
/// one serve the multigrid preconditioner).
[[nodiscard]] grid::BranchedGrid build_scene_grid(const io::Scene& scene, const grid::LabelGrid& labels, int max_level);

/// The message of a step that still created energy at 1/32 of dt (fem::StepStats::energy_guarded):
/// the loads or the time step are beyond what this object and level can follow.
[[nodiscard]] std::string energy_guard_message(const io::Scene& scene, int frame);

class SceneSimulation {
public:
    /// Throws the scene's InputError when a constraint or load box catches no node at `level`.
    SceneSimulation(const io::Scene& scene, const grid::BranchedGrid& grid, int level);

    [[nodiscard]] const fem::HexModel& model() const { return *m_model; }
    [[nodiscard]] fem::ImplicitSolver& solver() { return *m_solver; }
    [[nodiscard]] const fem::ImplicitSolver& solver() const { return *m_solver; }
    [[nodiscard]] const ModelSurface& surface() const { return *m_model_surface; }
    /// "Jacobi (matrix-free)", "warped Cholesky", "multigrid (3 levels)".
    [[nodiscard]] const std::string& linear_solver() const { return m_linear_solver; }

private:
    std::unique_ptr<fem::HexModel> m_model;
    std::unique_ptr<fem::ImplicitSolver> m_solver;
    std::unique_ptr<surface::EmbeddedSurface> m_surface;
    std::unique_ptr<ModelSurface> m_model_surface;
    std::string m_linear_solver;
};

} // namespace vox::app
