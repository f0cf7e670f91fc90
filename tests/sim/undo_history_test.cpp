// The viewer's undo history driven without a window, on both methods: strokes cut, undo puts
// the object back stroke by stroke, the oldest states drop beyond the capacity, and the
// simulation goes on from the state restored.

#include "io/scene.hpp"
#include "io/scene_object.hpp"
#include "sim/bundled_scene.hpp"
#include "sim/dbg_method.hpp"
#include "sim/frame_loop.hpp"
#include "sim/isxfem_method.hpp"
#include "sim/undo_history.hpp"

#include <gtest/gtest.h>

namespace vox::sim {
namespace {

io::Scene bar(io::SolverType type) { return test::bundled("bar_cut_isxfem.json", type); }

class UndoOnEachMethod : public ::testing::TestWithParam<io::SolverType> {};

TEST_P(UndoOnEachMethod, UndoPutsTheObjectBackStrokeByStroke)
{
    const io::Scene scene = bar(GetParam());
    auto labels = std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene));
    std::unique_ptr<Method> method;
    if (GetParam() != io::SolverType::isxfem) method = std::make_unique<DbgMethod>(scene, labels, 2, 2);
    else method = std::make_unique<IsxfemMethod>(scene, labels, 2);
    ToolPolicy tools(scene);
    FrameLoop loop(scene, *method, tools);
    UndoHistory history(2);
    EXPECT_FALSE(history.undo(*method)); // nothing yet
    std::vector<std::size_t> dofs;
    std::vector<surface::SurfaceMesh> surfaces;
    for (int stroke = 0; stroke < 3; ++stroke) { // three "strokes" of four frames each, the blade cutting down
        ASSERT_TRUE(history.before_stroke(*method));
        dofs.push_back(method->dof_count());
        surfaces.push_back(method->surface_mesh());
        for (int f = 0; f < 4; ++f) loop.next();
    }
    ASSERT_GT(method->dof_count(), dofs.front()) << "the blade cut (elements or enriched blocks added)";
    EXPECT_EQ(history.size(), 2u); // the first stroke's state dropped
    for (int k = 2; k >= 1; --k) {
        ASSERT_TRUE(history.undo(*method));
        tools.reset();
        EXPECT_EQ(method->dof_count(), dofs[static_cast<std::size_t>(k)]);
        const surface::SurfaceMesh now = method->surface_mesh();
        ASSERT_EQ(now.positions.size(), surfaces[static_cast<std::size_t>(k)].positions.size());
        for (std::size_t v = 0; v < now.positions.size(); ++v)
            ASSERT_TRUE(now.positions[v].isApprox(surfaces[static_cast<std::size_t>(k)].positions[v], 1e-12)) << v;
    }
    EXPECT_FALSE(history.undo(*method));
    for (int f = 0; f < 8; ++f) EXPECT_TRUE(loop.next().step.converged); // and it goes on from there
}

INSTANTIATE_TEST_SUITE_P(Methods, UndoOnEachMethod, ::testing::Values(io::SolverType::dbg, io::SolverType::isxfem, io::SolverType::shape_matching),
                         [](const auto& method) { return std::string(io::solver_type_name(method.param)); });

} // namespace
} // namespace vox::sim
