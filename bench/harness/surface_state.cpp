#include "bench/harness/surface_state.hpp"

namespace vox::bench {

SurfaceState surface_state(const sim::DbgMethod& method)
{
    const sim::DbgSimulation& sim = method.simulation();
    const std::vector<Eigen::Vector3d> u = sim.surface().displacements(sim.solver().positions());
    const auto& vertices = sim.surface().embedded().vertices();
    SurfaceState out;
    for (std::size_t i = 0; i < vertices.size(); ++i) {
        if (vertices[i].users == 0) continue;
        out.displacement_mm[vertices[i].key] = u[i] * 1e3;
        out.rest_mm[vertices[i].key] = method.grid().voxels().world_mm(vertices[i].rest);
    }
    return out;
}

} // namespace vox::bench
