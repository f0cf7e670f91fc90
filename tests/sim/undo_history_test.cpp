// The viewer's undo history driven without a window: strokes cut, undo puts the object back
// stroke by stroke, the oldest states drop beyond the capacity, and a method that cannot go back
// keeps nothing.

#include "io/scene.hpp"
#include "io/scene_object.hpp"
#include "sim/dbg_method.hpp"
#include "sim/frame_loop.hpp"
#include "sim/isxfem_method.hpp"
#include "sim/undo_history.hpp"

#include <gtest/gtest.h>

namespace vox::sim {
namespace {

io::Scene bar(io::SolverType type)
{
    io::Scene scene = io::load_scene(VOX_SOURCE_DIR "/data/scenes/bar_cut_isxfem.json");
    io::use_method(scene, type);
    return scene;
}

TEST(UndoHistory, UndoPutsTheObjectBackStrokeByStroke)
{
    const io::Scene scene = bar(io::SolverType::dbg);
    DbgMethod method(scene, std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene)), 2, 2);
    ToolPolicy tools(scene);
    FrameLoop loop(scene, method, tools);
    UndoHistory history(2);
    EXPECT_FALSE(history.undo(method)); // nothing yet
    std::vector<std::size_t> cuts;
    std::vector<surface::SurfaceMesh> surfaces;
    for (int stroke = 0; stroke < 3; ++stroke) { // three "strokes" of four frames each
        ASSERT_TRUE(history.before_stroke(method));
        cuts.push_back(method.cuts().size());
        surfaces.push_back(method.surface_mesh());
        for (int f = 0; f < 4; ++f) loop.next();
    }
    ASSERT_GT(method.cuts().size(), cuts.front()) << "the blade cut";
    EXPECT_EQ(history.size(), 2u); // the first stroke's state dropped
    for (int k = 2; k >= 1; --k) {
        ASSERT_TRUE(history.undo(method));
        tools.reset();
        EXPECT_EQ(method.cuts().size(), cuts[static_cast<std::size_t>(k)]);
        const surface::SurfaceMesh now = method.surface_mesh();
        ASSERT_EQ(now.positions.size(), surfaces[static_cast<std::size_t>(k)].positions.size());
        for (std::size_t v = 0; v < now.positions.size(); ++v)
            ASSERT_TRUE(now.positions[v].isApprox(surfaces[static_cast<std::size_t>(k)].positions[v], 1e-12));
    }
    EXPECT_FALSE(history.undo(method));
}

TEST(UndoHistory, AMethodThatCannotGoBackKeepsNothing)
{
    const io::Scene scene = bar(io::SolverType::isxfem);
    IsxfemMethod method(scene, std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene)), 2);
    UndoHistory history;
    EXPECT_FALSE(history.before_stroke(method));
    EXPECT_EQ(history.size(), 0u);
    EXPECT_FALSE(history.undo(method));
}

} // namespace
} // namespace vox::sim
