// The branched grid on the bundled liver CT segmentation: the counts published with the issue, and
// the condensation proved on real partial and multi-material cells.

#include "grid/branched_grid.hpp"

#include "core/morton.hpp"
#include "grid/condensation.hpp"
#include "io/selection.hpp"
#include "io/volume_reader.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

using namespace vox;
using namespace vox::grid;

namespace {

const std::vector<ElasticMaterial> k_materials{{lame_from_young_poisson(3e4, 0.45), 1060.0},
                                             {lame_from_young_poisson(1e5, 0.45), 1100.0}};

LabelGrid liver_labels(std::vector<std::int32_t> labels)
{
    io::Selection s;
    s.labels = std::move(labels);
    return io::select_voxels(io::read_volume(VOX_SOURCE_DIR "/data/liver.inr.gz"), s);
}

std::vector<CellVoxel> cell_voxels(const BranchedGrid& grid, int l, const Element& e)
{
    std::vector<CellVoxel> out;
    for (std::uint32_t v : e.voxels) {
        const Coord local = grid.voxels().coord(v) - e.cell * (1 << l);
        out.push_back({morton_encode(local.x(), local.y(), local.z()), grid.voxels().material(v)});
    }
    std::sort(out.begin(), out.end());
    return out;
}

} // namespace

TEST(LiverGrid, CellCountsMatchThePublishedFigures)
{
    const BranchedGrid grid(FineVoxels(liver_labels({255}), [](std::int32_t) { return 0; }), k_materials, 4);
    EXPECT_EQ(grid.voxels().alive_count(), 3160496u);
    EXPECT_EQ(grid.level(1).stats.cells, 408823u);
    EXPECT_EQ(grid.level(4).stats.cells, 1210u);
    const double voxel_mass = 1060.0 * grid.voxels().voxel_size_m().prod();
    EXPECT_NEAR(grid.total_mass_kg(), 3160496 * voxel_mass, 1e-9);
    for (int l = 1; l <= 4; ++l) {
        double mass = 0.0;
        const Level& lv = grid.level(l);
        for (std::uint32_t e = 0; e < lv.elements.size(); ++e)
            if (lv.elements[e].alive) mass += grid.mass(l, e).sum();
        EXPECT_NEAR(mass, grid.total_mass_kg(), 1e-10 * mass) << "level " << l;
        EXPECT_GE(lv.stats.elements, lv.stats.cells);
        EXPECT_LT(lv.stats.condensation_steps_direct, lv.stats.condensation_steps_recursive);
    }
}

TEST(LiverGrid, DirectRecursiveBruteForceAgreeOnRealMultiMaterialCells)
{
    // Liver (255) and its vessels (127) as two materials: cells where they meet are inhomogeneous.
    const BranchedGrid grid(FineVoxels(liver_labels({255, 127}), [](std::int32_t l) { return l == 127 ? 1 : 0; }),
                            k_materials, 3);
    int checked = 0, multi_material = 0;
    for (int l = 2; l <= 3; ++l) {
        const Level& lv = grid.level(l);
        for (std::uint32_t e = 0; e < lv.elements.size(); ++e) {
            const Element& el = lv.elements[e];
            // A sample of the partial cells, and every cell where the two materials meet.
            const bool sampled = e % 37 == 0 || (el.content.size() > 1 && multi_material < 100);
            if (!el.alive || !sampled || el.voxels.size() == std::size_t{1} << (3 * l)) continue;
            const auto voxels = cell_voxels(grid, l, el);
            const Eigen::Vector3d h = grid.voxels().voxel_size_m();
            const auto direct = condense_direct(voxels, l, h, grid.materials());
            const auto recursive = condense_recursive(voxels, l, h, grid.materials());
            const auto brute = condense_brute_force(voxels, l, h, grid.materials());
            const Matrix24d k = grid.stiffness(l, e);
            const double scale = brute.stiffness.norm();
            EXPECT_LT((direct.stiffness - brute.stiffness).norm(), 1e-10 * scale);
            EXPECT_LT((recursive.stiffness - brute.stiffness).norm(), 1e-10 * scale);
            EXPECT_LT((k - brute.stiffness).norm(), 1e-10 * scale);
            EXPECT_LT((grid.mass(l, e) - brute.mass).norm(), 1e-10 * brute.mass.norm());
            EXPECT_LT(direct.steps, recursive.steps);
            // Rigid translations and infinitesimal rotations about the cell's corner.
            const Eigen::Vector3d cell = static_cast<double>(1 << l) * h;
            for (int axis = 0; axis < 3; ++axis) {
                Vector24d t = Vector24d::Zero(), r = Vector24d::Zero();
                for (int c = 0; c < 8; ++c) {
                    t[3 * c + axis] = 1.0;
                    const Eigen::Vector3d x(cell.x() * (c & 1), cell.y() * ((c >> 1) & 1), cell.z() * ((c >> 2) & 1));
                    r.segment<3>(3 * c) = Eigen::Vector3d::Unit(axis).cross(x);
                }
                EXPECT_LT((k * t).norm(), 1e-10 * scale);
                EXPECT_LT((k * r).norm(), 1e-10 * scale * cell.norm());
            }
            ++checked;
            multi_material += el.content.size() > 1;
        }
    }
    EXPECT_GT(checked, 100);
    EXPECT_GT(multi_material, 5);
}
