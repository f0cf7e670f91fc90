// Supports and loads on the material (sim/supports.hpp), against the voxels found by visiting the
// whole grid: a box holds the same voxels at every level; each held voxel holds a corner of its own element within half a cell of it, and every
// held node lies within half a cell of a held voxel, so a layer thinner than a cell is held at
// every level; of superimposed elements only the one whose material the box holds is held; a
// load's force and moment are the same at every level; a box holding no voxel centre is an error
// that names it.

#include "fem/hex_model.hpp"
#include "grid/branched_grid.hpp"
#include "grid/phantom.hpp"
#include "io/scene.hpp"
#include "io/scene_object.hpp"
#include "core/error.hpp"
#include "sim/dbg_simulation.hpp"
#include "io/box.hpp"
#include "sim/supports.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <set>

namespace vox::sim {
namespace {

/// A beam of 1 mm voxels (centres at 0, 1, 2 ... mm, element corners at -0.5 + k 2^level).
grid::BranchedGrid beam_grid(const Eigen::Vector3i& size, int max_level)
{
    grid::PhantomSpec spec = grid::default_phantom(grid::PhantomShape::beam);
    spec.size_mm = size.cast<double>();
    spec.voxel_mm = 1.0;
    const grid::ElasticMaterial steel{grid::lame_from_young_poisson(1e5, 0.3), 1000.0};
    return grid::BranchedGrid(grid::FineVoxels(grid::make_phantom(spec), [](std::int32_t) { return 0; }), {steel}, max_level);
}

/// A voxel in a box, found by visiting every voxel of the grid: its centre (world mm) and the
/// model element holding it.
struct Found {
    Eigen::Vector3d centre;
    std::uint32_t element = 0;
};

std::vector<Found> voxels_in_box(const grid::BranchedGrid& grid, const fem::HexModel& model, int level, const Eigen::Vector3d& lo,
                                 const Eigen::Vector3d& hi)
{
    std::vector<std::uint32_t> model_element(level == 0 ? grid.voxels().slots() : grid.level(level).elements.size(), grid::no_index);
    for (std::uint32_t e = 0; e < model.elements().size(); ++e) model_element[model.elements()[e].grid_element] = e;
    std::vector<Found> out;
    for (std::uint32_t v = 0; v < grid.voxels().slots(); ++v) {
        if (!grid.voxels().alive(v)) continue;
        const Eigen::Vector3d c = grid.voxels().world_mm(grid.voxels().coord(v).cast<double>());
        if (io::in_box(c, lo, hi)) out.push_back({c, model_element[level == 0 ? v : grid.element_of(v, level)]});
    }
    return out;
}

TEST(Supports, ABoxHoldsTheSameMaterialAtEveryLevelAndEachLevelHoldsItWithinHalfACell)
{
    const grid::BranchedGrid grid = beam_grid({32, 8, 8}, 3);
    // Two boxes: five layers of voxels ending inside a level-3 cell, and one layer in the middle
    // of the beam that no level's corners lie on.
    for (const auto& [lo, hi] : {std::pair{Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(4.2, 9, 9)},
                                 std::pair{Eigen::Vector3d(9.8, -1, -1), Eigen::Vector3d(10.2, 9, 9)}}) {
        for (int level = 0; level <= 3; ++level) {
            const fem::HexModel model(grid, level);
            BoxMaterial box(lo, hi);
            box.update(grid, level, nullptr);
            const std::vector<Found> voxels = voxels_in_box(grid, model, level, lo, hi);
            EXPECT_EQ(box.voxel_count(model), voxels.size()) << "level " << level;
            EXPECT_EQ(voxels.size(), static_cast<std::size_t>((hi.x() > 5 ? 1 : 5) * 8 * 8)) << "level " << level;

            const std::vector<std::uint32_t> held = box.supported_nodes(model);
            ASSERT_FALSE(held.empty()) << "level " << level;
            const double half = 0.5 * (1 << level) + 1e-9; // mm, a voxel being 1 mm
            // Every held voxel has a held corner of its own element within half a cell per axis
            // (at level 0, the voxel's own corners).
            const std::set<std::uint32_t> held_set(held.begin(), held.end());
            for (const Found& v : voxels) {
                bool near = false;
                for (std::uint32_t n : model.elements()[v.element].dof_node)
                    near = near || (held_set.count(n) && ((model.rest_positions()[n] * 1e3 - v.centre).cwiseAbs().array() <= half).all());
                EXPECT_TRUE(near) << "level " << level << ": voxel at " << v.centre.transpose() << " holds no corner beside it";
            }
            // Every held node lies within half a cell of a held voxel.
            for (std::uint32_t n : held) {
                bool near = false;
                for (const Found& v : voxels) near = near || ((model.rest_positions()[n] * 1e3 - v.centre).cwiseAbs().array() <= half).all();
                EXPECT_TRUE(near) << "level " << level << ": node at " << (model.rest_positions()[n] * 1e3).transpose() << " is held by nothing near";
            }
        }
    }
}

TEST(Supports, OfSuperimposedElementsOnlyTheOneWhoseMaterialTheBoxHoldsIsHeld)
{
    const grid::LabelGrid labels = grid::make_phantom(grid::default_phantom(grid::PhantomShape::utube));
    const grid::ElasticMaterial soft{grid::lame_from_young_poisson(1e5, 0.3), 1000.0};
    const grid::BranchedGrid grid(grid::FineVoxels(labels, [](std::int32_t) { return 0; }), {soft}, 3);
    const int level = 3;
    const fem::HexModel model(grid, level);
    const grid::Level& lv = grid.level(level);
    // A cell holding two elements (the U's two arms); the box around one element's voxel centres.
    std::uint32_t a = grid::no_index, b = grid::no_index;
    for (std::uint32_t e = 0; e < model.elements().size() && a == grid::no_index; ++e) {
        const grid::Element& g = lv.elements[model.elements()[e].grid_element];
        const std::vector<std::uint32_t> in_cell = lv.cell_elements(g.code);
        if (in_cell.size() < 2) continue;
        a = e;
        for (std::uint32_t f = 0; f < model.elements().size(); ++f)
            if (f != e && lv.elements[model.elements()[f].grid_element].code == g.code) b = f;
    }
    ASSERT_NE(a, grid::no_index) << "the U-tube at level 3 has no cell with two elements";
    ASSERT_NE(b, grid::no_index);
    Eigen::AlignedBox3d box;
    for (std::uint32_t v : lv.elements[model.elements()[a].grid_element].voxels)
        box.extend(grid.voxels().world_mm(grid.voxels().coord(v).cast<double>()));
    for (const Found& v : voxels_in_box(grid, model, level, box.min(), box.max()))
        ASSERT_EQ(v.element, a) << "the box reaches the other arm's material";
    BoxMaterial material(box.min(), box.max());
    material.update(grid, level, nullptr);
    const std::vector<std::uint32_t> held = material.supported_nodes(model);
    ASSERT_FALSE(held.empty());
    const auto& own = model.elements()[a].dof_node;
    const auto& other = model.elements()[b].dof_node;
    for (std::uint32_t n : held) {
        EXPECT_NE(std::find(own.begin(), own.end(), n), own.end());
        // Corners the two arms share (where they meet in a neighbouring cell) may be held; a corner
        // of the other arm's own is not.
        const bool shared = std::find(own.begin(), own.end(), n) != own.end() && std::find(other.begin(), other.end(), n) != other.end();
        if (!shared) EXPECT_EQ(std::find(other.begin(), other.end(), n), other.end());
    }
}

TEST(Supports, ALoadHasTheSameForceAndMomentAtEveryLevel)
{
    const grid::BranchedGrid grid = beam_grid({32, 8, 8}, 3);
    // The top layer of the beam's last 7 mm: a box ending inside cells of every level above 0.
    const Eigen::Vector3d lo(25, -1, 6.5), hi(40, 9, 9);
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (int level = 0; level <= 3; ++level) {
        const fem::HexModel model(grid, level);
        const std::vector<Found> voxels = voxels_in_box(grid, model, level, lo, hi);
        ASSERT_EQ(voxels.size(), std::size_t{7 * 8 * 1});
        if (level == 0)
            for (const Found& v : voxels) mean += v.centre / static_cast<double>(voxels.size());
        BoxMaterial box(lo, hi);
        box.update(grid, level, nullptr);
        double total = 0.0;
        Eigen::Vector3d at = Eigen::Vector3d::Zero(); // where the force acts: its moment over its size
        for (const auto& [n, share] : box.load_shares(model)) {
            EXPECT_GT(share, 0.0);
            total += share;
            at += share * model.rest_positions()[n] * 1e3;
        }
        EXPECT_NEAR(total, 1.0, 1e-12) << "level " << level;
        EXPECT_LT((at - mean).norm(), 1e-9) << "level " << level << ": the load acts at " << at.transpose() << ", not at "
                                            << mean.transpose();
    }
}

TEST(Supports, AfterACutMeasuringOnlyTheChangedElementsGivesWhatMeasuringAllGives)
{
    grid::BranchedGrid grid = beam_grid({32, 8, 8}, 3);
    const int level = 2;
    const Eigen::Vector3d lo(-1, -1, -1), hi(12.2, 9, 9); // a load box the same way
    BoxMaterial kept(lo, hi);
    kept.update(grid, level, nullptr);
    // A notch through the box's material (voxels removed) and a slit beside it (faces opened)
    // that splits cells into superimposed elements.
    std::vector<grid::Coord> removed;
    std::vector<std::pair<grid::Coord, int>> faces;
    for (int y = 0; y < 8; ++y)
        for (int z = 3; z < 8; ++z) {
            removed.emplace_back(6, y, z);
            removed.emplace_back(7, y, z);
            faces.push_back({grid::Coord(10, y, z), 0}); // between x = 10 and 11
        }
    const grid::UpdateReport report = grid.update(removed, faces);
    std::vector<unsigned char> changed(grid.level(level).elements.size(), 0);
    for (const auto& [e, from] : report.levels[level].created) changed[e] = 1;
    for (std::uint32_t e : report.levels[level].updated) changed[e] = 1;
    kept.update(grid, level, &changed);

    const fem::HexModel model(grid, level);
    BoxMaterial fresh(lo, hi);
    fresh.update(grid, level, nullptr);
    EXPECT_EQ(kept.voxel_count(model), voxels_in_box(grid, model, level, lo, hi).size());
    EXPECT_EQ(kept.voxel_count(model), std::size_t{13 * 8 * 8 - 2 * 8 * 5});
    EXPECT_EQ(kept.supported_nodes(model), fresh.supported_nodes(model));
    EXPECT_EQ(kept.load_shares(model), fresh.load_shares(model));
}

TEST(Supports, ABoxHoldingNoVoxelCentreIsAnErrorNamingIt)
{
    // Voxel centres at 0 .. 19 mm along x: the slab x in [-1, -0.6] holds none (it reaches the
    // element corners at -0.5 only at no level).
    const nlohmann::json doc = {
        {"object", {{"phantom", {{"shape", "beam"}, {"size_mm", {20, 4, 4}}, {"voxel_mm", 1}}}, {"levels", 1}}},
        {"constraints", {{{"type", "fixed"}, {"box_mm", {{-1, -1, -1}, {-0.6, 5, 5}}}}}},
    };
    const io::Scene scene = io::parse_scene(doc, ::testing::TempDir(), "supports.json");
    const grid::LabelGrid labels = io::load_scene_object(scene);
    try {
        io::check_constraints(scene, labels);
        FAIL() << "no error";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("supports.json: constraints[0].box_mm: holds no voxel centre of the object"), std::string::npos)
            << e.what();
        EXPECT_NE(std::string(e.what()).find("(0, 0, 0) to (19, 3, 3) mm"), std::string::npos) << e.what();
    }
}

} // namespace
} // namespace vox::sim
