// The tetrahedra of a branched-grid level: six per element on the element's own nodes, positively
// oriented; a full cell's six tetrahedra each hold a sixth of its material (voxel centres on the
// planes between them shared out), and over a partly filled object the tetrahedra hold its mass
// (up to the 1e-3 floor of empty ones); every rest point of an element is located in one of its
// tetrahedra with barycentric coordinates that give it back.

#include "isxfem/grid_tets.hpp"

#include "grid/phantom.hpp"

#include <gtest/gtest.h>

using namespace vox;
using namespace vox::isxfem;

namespace {

grid::BranchedGrid block_grid(const Eigen::Vector3d& size_mm, int levels)
{
    grid::PhantomSpec spec = grid::default_phantom(grid::PhantomShape::beam);
    spec.size_mm = size_mm;
    const std::vector<grid::ElasticMaterial> clay{{grid::lame_from_young_poisson(1e5, 0.3), 1500.0}};
    return grid::BranchedGrid(grid::FineVoxels(grid::make_phantom(spec), [](std::int32_t) { return 0; }), clay, levels);
}

double tet_mass(const GridTets& t, std::size_t k) { return t.materials[t.material[k]].density_kg_m3 * signed_volume(t.mesh.corners(k)); }

} // namespace

TEST(GridTets, FullCellsShareTheirMaterialEvenly)
{
    for (int level : {1, 2}) {
        SCOPED_TRACE("level " + std::to_string(level));
        const grid::BranchedGrid g = block_grid({8, 8, 8}, level);
        const fem::HexModel model(g, level);
        const GridTets t = tets_from_model(g, model);
        ASSERT_EQ(t.mesh.tets.size(), 6 * model.elements().size());
        double mass = 0.0;
        for (std::size_t k = 0; k < t.mesh.tets.size(); ++k) {
            EXPECT_GT(signed_volume(t.mesh.corners(k)), 0.0);
            EXPECT_NEAR(t.fill[k], 1.0, 1e-12);
            mass += tet_mass(t, k);
        }
        EXPECT_NEAR(mass, 1500.0 * 512e-9, 1e-12); // 8 x 8 x 8 voxels of 1 mm^3
    }
}

TEST(GridTets, APartlyFilledObjectKeepsItsMassAndLocatesItsPoints)
{
    const grid::BranchedGrid g = block_grid({10, 10, 6}, 2); // cells of 4 mm: partly filled at the far faces
    const fem::HexModel model(g, 2);
    const GridTets t = tets_from_model(g, model);
    double mass = 0.0, floor = 0.0;
    for (std::size_t k = 0; k < t.mesh.tets.size(); ++k) {
        mass += tet_mass(t, k);
        if (t.fill[k] <= 1e-3) floor += tet_mass(t, k);
    }
    EXPECT_NEAR(mass - floor, 1500.0 * 600e-9, 1e-3 * 1500.0 * 600e-9);
    // Points of element 0 come back from their barycentric coordinates.
    const auto& el = model.elements()[0];
    for (const Eigen::Vector3d& w : {Eigen::Vector3d(0.1, 0.2, 0.3), Eigen::Vector3d(0.9, 0.5, 0.5), Eigen::Vector3d(0.5, 0.5, 0.5)}) {
        Eigen::Vector3d x = Eigen::Vector3d::Zero();
        for (int c = 0; c < 8; ++c)
            x += ((c & 1 ? w.x() : 1 - w.x()) * (c & 2 ? w.y() : 1 - w.y()) * (c & 4 ? w.z() : 1 - w.z())) *
                 model.rest_positions()[el.dof_node[static_cast<std::size_t>(c)]];
        const auto [tet, bary] = locate(t.mesh, 0, x);
        EXPECT_GE(tet, 0u);
        EXPECT_LT(tet, 6u);
        Eigen::Vector3d back = Eigen::Vector3d::Zero();
        for (std::size_t c = 0; c < 4; ++c) back += bary[c] * t.mesh.nodes[t.mesh.tets[tet][c]];
        EXPECT_LT((back - x).norm(), 1e-12);
    }
}
