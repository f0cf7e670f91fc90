#include "sim/isxfem_fem_mesh.hpp"

#include "grid/label_grid.hpp"
#include "isxfem/cut_tetrahedron.hpp"
#include "sim/isxfem_simulation.hpp"
#include "sim/von_mises.hpp"

#include <Eigen/LU>

#include <map>
#include <numeric>

namespace vox::sim {
namespace {

std::uint32_t root(std::vector<std::uint32_t>& parent, std::uint32_t a)
{
    while (parent[a] != a) a = parent[a] = parent[parent[a]];
    return a;
}

std::array<double, 4> bary_of(const Eigen::Vector3d& r) { return {1.0 - r.x() - r.y() - r.z(), r.x(), r.y(), r.z()}; }

/// The pieces of the reference tetrahedron between all of the element's cuts: each cut splits the
/// pieces the earlier ones left, in their own reference frame mapped back.
std::vector<isxfem::Piece> split_by_cuts(const isxfem::XfemElement& e)
{
    std::vector<isxfem::Piece> pieces{isxfem::whole_tetrahedron()};
    for (std::size_t j = 0; j < e.cuts.size(); ++j) {
        std::vector<isxfem::Piece> next;
        for (const isxfem::Piece& p : pieces) {
            std::array<double, 4> phi{};
            for (int k = 0; k < 4; ++k) phi[static_cast<std::size_t>(k)] = e.level_at(j, bary_of(k == 0 ? p.corner : Eigen::Vector3d(p.corner + p.edges.col(k - 1))));
            const isxfem::CutSides sides = isxfem::split_reference_tetrahedron(phi);
            for (const auto* side : {&sides.negative, &sides.positive})
                for (const isxfem::Piece& s : *side) {
                    isxfem::Piece mapped;
                    mapped.corner = p.corner + p.edges * s.corner;
                    mapped.edges = p.edges * s.edges;
                    mapped.volume = s.volume * std::abs(p.edges.determinant());
                    if (mapped.volume > 1e-9) next.push_back(mapped); // slivers say nothing in a picture
                }
        }
        pieces = std::move(next);
    }
    return pieces;
}

} // namespace

io::VtuMesh isxfem_fem_mesh(const IsxfemSimulation& sim, const grid::LabelGrid& labels, int level)
{
    const isxfem::XfemModel& model = sim.model();
    const std::vector<Eigen::Vector3d>& x = sim.solver().state();
    const std::vector<Eigen::Vector3d>& v = sim.solver().velocities();
    const std::vector<Eigen::Vector3d>& rest = model.mesh().nodes;
    const std::size_t nodes = model.node_count();
    const Eigen::Matrix4d world_to_index = labels.index_to_world().inverse();

    io::VtuMesh mesh;
    mesh.cell_type = io::VtuMesh::k_tetra;
    std::vector<Eigen::Vector3d> displacement, velocity;
    for (std::size_t n = 0; n < nodes; ++n) {
        mesh.points.push_back(1e3 * x[n]);
        displacement.push_back(1e3 * (x[n] - rest[n]));
        velocity.push_back(1e3 * v[n]);
    }
    std::vector<std::uint32_t> parent(nodes);
    std::iota(parent.begin(), parent.end(), 0u);
    std::vector<double> region, stress, label;
    std::vector<std::uint32_t> cell_root; // per cell: a union-find entry it belongs to

    const auto label_at = [&](const Eigen::Vector3d& rest_m) {
        const Eigen::Vector3d index = (world_to_index * (1e3 * rest_m).homogeneous()).head<3>();
        return static_cast<double>(labels.get(index.array().round().cast<int>().matrix()));
    };
    for (const isxfem::XfemElement& e : model.elements()) {
        const grid::Lame lame = model.materials()[e.material].lame;
        Eigen::Matrix3d rest_edges;
        for (int k = 0; k < 3; ++k) rest_edges.col(k) = rest[e.node[static_cast<std::size_t>(k + 1)]] - rest[e.node[0]];
        const Eigen::Matrix3d rest_inverse = rest_edges.inverse();
        Eigen::Vector3d rest_centroid = Eigen::Vector3d::Zero();
        for (const std::uint32_t n : e.node) rest_centroid += 0.25 * rest[n];
        if (!e.is_cut()) {
            Eigen::Matrix3d now;
            for (int k = 0; k < 3; ++k) now.col(k) = x[e.node[static_cast<std::size_t>(k + 1)]] - x[e.node[0]];
            for (const std::uint32_t n : e.node) {
                mesh.connectivity.push_back(n);
                parent[root(parent, n)] = root(parent, e.node[0]);
            }
            cell_root.push_back(e.node[0]);
            region.push_back(-1.0);
            stress.push_back(von_mises_pa(now * rest_inverse, lame));
            label.push_back(label_at(rest_centroid));
            continue;
        }
        // Each side's sub-tetrahedra, placed by that side's field; joined to the nodes on its side.
        std::map<unsigned, std::uint32_t> side_entry;
        for (const isxfem::Piece& p : split_by_cuts(e)) {
            std::array<Eigen::Vector3d, 4> corner{p.corner, p.corner + p.edges.col(0), p.corner + p.edges.col(1), p.corner + p.edges.col(2)};
            if (p.edges.determinant() < 0.0) std::swap(corner[1], corner[2]); // positive orientation, as VTK draws it
            const unsigned pattern = e.region_at(bary_of(0.25 * (corner[0] + corner[1] + corner[2] + corner[3])));
            if (!side_entry.count(pattern)) {
                side_entry[pattern] = static_cast<std::uint32_t>(parent.size());
                parent.push_back(static_cast<std::uint32_t>(parent.size()));
                for (std::size_t c = 0; c < 4; ++c)
                    if (e.node_region(c) == pattern) parent[root(parent, side_entry[pattern])] = root(parent, e.node[c]);
            }
            Eigen::Vector3d piece_rest = Eigen::Vector3d::Zero();
            for (const Eigen::Vector3d& r : corner) {
                const std::array<double, 4> b = bary_of(r);
                Eigen::Vector3d at = Eigen::Vector3d::Zero(), was = Eigen::Vector3d::Zero(), speed = Eigen::Vector3d::Zero();
                for (std::size_t c = 0; c < 4; ++c) {
                    at += b[c] * e.region_node(c, pattern, x);
                    speed += b[c] * e.region_node(c, pattern, v);
                    was += b[c] * rest[e.node[c]];
                }
                mesh.connectivity.push_back(static_cast<std::uint32_t>(mesh.points.size()));
                mesh.points.push_back(1e3 * at);
                displacement.push_back(1e3 * (at - was));
                velocity.push_back(1e3 * speed);
                piece_rest += 0.25 * was;
            }
            Eigen::Matrix3d now;
            for (int k = 0; k < 3; ++k)
                now.col(k) = e.region_node(static_cast<std::size_t>(k + 1), pattern, x) - e.region_node(0, pattern, x);
            cell_root.push_back(side_entry[pattern]);
            region.push_back(pattern);
            stress.push_back(von_mises_pa(now * rest_inverse, lame));
            label.push_back(label_at(piece_rest));
        }
    }
    mesh.point_vectors = {{"displacement_mm", std::move(displacement)}, {"velocity_mm_s", std::move(velocity)}};
    const std::size_t cells = region.size();
    std::map<std::uint32_t, double> numbers;
    std::vector<double> piece(cells);
    for (std::size_t i = 0; i < cells; ++i) {
        const std::uint32_t r = root(parent, cell_root[i]);
        piece[i] = numbers.emplace(r, static_cast<double>(numbers.size())).first->second;
    }
    std::map<std::int32_t, std::vector<double>> fraction;
    for (std::size_t i = 0; i < cells; ++i) {
        auto& f = fraction[static_cast<std::int32_t>(label[i])];
        f.resize(cells, 0.0);
        f[i] = 1.0;
    }
    mesh.cell_scalars = {{"level", std::vector<double>(cells, level)},
                         {"piece", std::move(piece)},
                         {"dominant_label", std::move(label)},
                         {"plastic_strain", std::vector<double>(cells, 0.0)},
                         {"water", std::vector<double>(cells, 0.0)},
                         {"von_mises_pa", std::move(stress)},
                         {"region", std::move(region)}};
    for (auto& [l, values] : fraction) mesh.cell_scalars.emplace_back("fraction_label_" + std::to_string(l), std::move(values));
    return mesh;
}

} // namespace vox::sim
