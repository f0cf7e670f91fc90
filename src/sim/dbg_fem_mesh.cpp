#include "sim/dbg_fem_mesh.hpp"

#include "sim/dbg_simulation.hpp"
#include "sim/von_mises.hpp"

#include <map>
#include <numeric>

namespace vox::sim {
namespace {

/// Our corners have bits (x, y, z); VTK's hexahedron goes round the bottom face, then the top.
constexpr std::array<int, 8> k_vtk_corner{0, 1, 3, 2, 4, 5, 7, 6};

std::uint32_t root(std::vector<std::uint32_t>& parent, std::uint32_t a)
{
    while (parent[a] != a) a = parent[a] = parent[parent[a]];
    return a;
}

} // namespace

io::VtuMesh dbg_fem_mesh(const DbgSimulation& sim)
{
    const fem::HexModel& model = sim.model();
    const fem::ImplicitSolver& solver = sim.solver();
    const std::vector<Eigen::Vector3d>& x = solver.positions();
    const std::vector<Eigen::Vector3d>& v = solver.velocities();
    const std::vector<Eigen::Vector3d>& rest = model.rest_positions();
    const std::vector<fem::HexElement>& elements = model.elements();

    io::VtuMesh mesh;
    mesh.cell_type = io::VtuMesh::k_hexahedron;
    std::vector<Eigen::Vector3d> displacement(x.size()), velocity(x.size());
    for (std::size_t n = 0; n < x.size(); ++n) {
        mesh.points.push_back(1e3 * x[n]);
        displacement[n] = 1e3 * (x[n] - rest[n]);
        velocity[n] = 1e3 * v[n];
    }
    mesh.point_vectors = {{"displacement_mm", std::move(displacement)}, {"velocity_mm_s", std::move(velocity)}};

    // Pieces: elements joined through shared nodes.
    std::vector<std::uint32_t> parent(x.size());
    std::iota(parent.begin(), parent.end(), 0u);
    for (const fem::HexElement& e : elements)
        for (int c = 1; c < 8; ++c) parent[root(parent, e.dof_node[static_cast<std::size_t>(c)])] = root(parent, e.dof_node[0]);
    std::map<std::uint32_t, double> piece_number;

    // Labels: each voxel counts for the element that holds it.
    std::vector<std::map<std::int32_t, double>> labels(elements.size());
    std::map<std::int32_t, int> all_labels;
    const grid::FineVoxels& voxels = sim.surface().grid().voxels();
    for (std::uint32_t s = 0; s < voxels.slots(); ++s) {
        if (!voxels.alive(s)) continue;
        Eigen::Vector3d local;
        const std::uint32_t e = sim.surface().voxel_element(s, local);
        if (e >= elements.size()) continue;
        labels[e][voxels.label(s)] += 1.0;
        all_labels[voxels.label(s)] = 0;
    }

    std::vector<double> level(elements.size(), model.level()), piece(elements.size()), dominant(elements.size()),
        plastic(elements.size()), water(elements.size()), von_mises(elements.size());
    std::map<std::int32_t, std::vector<double>> fraction;
    for (const auto& [label, unused] : all_labels) fraction[label].assign(elements.size(), 0.0);
    const Eigen::Matrix3d& frame = model.frame();
    for (std::size_t i = 0; i < elements.size(); ++i) {
        const fem::HexElement& e = elements[i];
        for (const int c : k_vtk_corner) mesh.connectivity.push_back(e.dof_node[static_cast<std::size_t>(c)]);
        const std::uint32_t r = root(parent, e.dof_node[0]);
        piece[i] = piece_number.emplace(r, static_cast<double>(piece_number.size())).first->second;
        double total = 0.0, most = -1.0;
        for (const auto& [label, count] : labels[i]) {
            total += count;
            if (count > most) {
                most = count;
                dominant[i] = label;
            }
        }
        for (const auto& [label, count] : labels[i]) fraction[label][i] = count / total;
        const auto element = static_cast<std::uint32_t>(i);
        const Eigen::Matrix3d plastic_strain = solver.plastic_strain(element);
        plastic[i] = plastic_strain.norm();
        water[i] = solver.water(element);
        // Deformation gradient at the centroid, in the index-aligned frame of the element's data.
        Eigen::Matrix3d f = Eigen::Matrix3d::Zero();
        for (int c = 0; c < 8; ++c) f += (frame.transpose() * x[e.dof_node[static_cast<std::size_t>(c)]]) * e.gradient.row(c);
        von_mises[i] = von_mises_pa(f, model.materials()[static_cast<std::size_t>(e.material)].lame, plastic_strain,
                                    solver.stiffness_scale(element, e.material));
    }
    mesh.cell_scalars = {{"level", std::move(level)},        {"piece", std::move(piece)},
                         {"dominant_label", std::move(dominant)}, {"plastic_strain", std::move(plastic)},
                         {"water", std::move(water)},        {"von_mises_pa", std::move(von_mises)}};
    for (auto& [label, values] : fraction) mesh.cell_scalars.emplace_back("fraction_label_" + std::to_string(label), std::move(values));
    return mesh;
}

} // namespace vox::sim
