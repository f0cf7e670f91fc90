#pragma once
// Strokes of a separating blade through objects that move while they are cut, run by either
// method, and what they opened counted (tests/sim/cut_sheets.hpp): the one-sheet tests and their
// long random sample.

#include "cut_sheets.hpp"
#include "io/scene.hpp"
#include "io/scene_object.hpp"
#include "sim/dbg_method.hpp"
#include "sim/frame_loop.hpp"
#include "sim/isxfem_method.hpp"
#include "sim/method_factory.hpp"
#include "sim/tool_policy.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <string>

namespace vox::sim::test {

using vox::test::count_cracks;
using vox::test::count_sheets;
using vox::test::SheetCount;

/// Runs the scene's whole script by `type` and counts what its cuts opened.
inline SheetCount run_and_count(io::Scene scene, io::SolverType type, const std::string& name)
{
    io::use_method(scene, type);
    auto labels = std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene));
    std::unique_ptr<Method> method = open_method(scene, labels).method;
    const auto* dbg = dynamic_cast<const DbgMethod*>(method.get());
    const std::size_t voxels_before = dbg ? dbg->grid().voxels().alive_count() : 0;
    ToolPolicy tools(scene);
    FrameLoop loop(scene, *method, tools);
    const int frames = static_cast<int>(std::lround(scene.script.back().t_s / scene.solver.dt_s));
    for (int f = 0; f < frames; ++f) loop.next();
    SheetCount n;
    if (dbg) {
        std::vector<std::pair<grid::Coord, int>> faces;
        for (const CutRecord& c : dbg->cuts()) faces.insert(faces.end(), c.faces.begin(), c.faces.end());
        n = count_sheets(dbg->grid().voxels(), faces);
        EXPECT_EQ(n.voxels, voxels_before) << name << ": separating loses no voxel";
    } else {
        const auto& isxfem = dynamic_cast<const IsxfemMethod&>(*method);
        n = count_cracks(isxfem.simulation().model(), isxfem.surface_mesh(), labels->voxel_size().prod());
    }
    std::printf("%s (%s): %zu %s, %zu sheets, %zu parallel pairs, %zu pieces, %zu slivers\n", name.c_str(), method->name(), n.faces,
                dbg ? "faces" : "cut tetrahedra", n.sheets, n.parallel_pairs, n.pieces, n.slivers);
    return n;
}

inline const nlohmann::json k_rod = {{"phantom", {{"shape", "beam"}, {"size_mm", {100, 10, 10}}, {"voxel_mm", 1.0}}}, {"levels", 2}};
inline const nlohmann::json k_both_ends = {{{"type", "fixed"}, {"box_mm", {{-1, -1, -1}, {2, 11, 11}}}},
                                    {{"type", "fixed"}, {"box_mm", {{98, -1, -1}, {101, 11, 11}}}}};
inline const nlohmann::json k_one_end = {{{"type", "fixed"}, {"box_mm", {{-1, -1, -1}, {2, 11, 11}}}}};

inline nlohmann::json blade_scene(const nlohmann::json& object, double youngs_pa, const nlohmann::json& constraints, const nlohmann::json& script,
                           bool two_phase = false, const nlohmann::json& blade_mm = {70, 1, 60})
{
    nlohmann::json blade = {{"name", "blade"}, {"shape", "blade"}, {"size_mm", blade_mm}, {"cut_mode", "separate"}};
    if (two_phase) blade["two_phase"] = true;
    return {{"object", object},
            {"materials", {{"default", {{"youngs_modulus_pa", youngs_pa}, {"poisson_ratio", 0.3}, {"density_kg_m3", 1000}}}}},
            {"solver", {{"type", "dbg"}, {"dt_s", 0.01}}},
            {"gravity_m_s2", {0, 0, -9.81}},
            {"constraints", constraints},
            {"tools", {blade}},
            {"script", script}};
}

inline nlohmann::json pose(double t_s, const Eigen::Vector3d& p, const Eigen::Quaterniond& o)
{
    return {{"t_s", t_s}, {"tool", "blade"}, {"position_mm", {p.x(), p.y(), p.z()}}, {"orientation_wxyz", {o.w(), o.x(), o.y(), o.z()}}};
}

inline io::Scene parse(const nlohmann::json& doc, const std::string& name) { return io::parse_scene(doc, ::testing::TempDir(), name); }

/// A blade edge first along its own plane, or straight down, through a point of the rod.
struct StraightStroke {
    double x = 50, yaw = 0, roll = 0; ///< where along the rod; the blade turned about the vertical, then tilted about the rod's axis
    bool along_plane = true;
};

inline io::Scene rod_stroke(const StraightStroke& s, double youngs_pa, const nlohmann::json& constraints, bool two_phase, const std::string& name)
{
    const Eigen::Quaterniond o = Eigen::AngleAxisd(s.roll, Eigen::Vector3d::UnitX()) * Eigen::AngleAxisd(M_PI / 2 + s.yaw, Eigen::Vector3d::UnitZ());
    const Eigen::Vector3d from(s.x, 5, 5), way = s.along_plane ? Eigen::Vector3d(o * -Eigen::Vector3d::UnitZ()) : Eigen::Vector3d(0, 0, -1);
    return parse(blade_scene(k_rod, youngs_pa, constraints, {pose(0.0, from - 40.0 * way, o), pose(1.0, from + 30.0 * way, o)}, two_phase),
                 name);
}

/// A plate lying flat, held along two opposite edges; a short blade plunges through it and draws
/// an arc turning by `turn` radians (its plane along the way it goes), a curved slit. (A blade
/// longer than the arc is wide carves the plate as its ends swing round: that is no slit.)
inline io::Scene curved_stroke(double radius_mm, double turn, double start_heading, const std::string& name)
{
    const nlohmann::json plate = {{"phantom", {{"shape", "beam"}, {"size_mm", {80, 80, 8}}, {"voxel_mm", 1.0}}}, {"levels", 2}};
    const nlohmann::json held = {{{"type", "fixed"}, {"box_mm", {{-1, -1, -1}, {2, 81, 9}}}}, {{"type", "fixed"}, {"box_mm", {{78, -1, -1}, {81, 81, 9}}}}};
    const Eigen::Vector3d centre(40, 40, 0);
    const auto along = [&](double a) { // the blade (8 x 1 x 30 mm) on the arc at angle a, its edge 6 mm under the plate
        const double heading = start_heading + a;
        const Eigen::Vector3d at = centre + radius_mm * Eigen::Vector3d(std::cos(heading - M_PI / 2), std::sin(heading - M_PI / 2), 0) +
                                   Eigen::Vector3d(0, 0, 9);
        return std::pair{at, Eigen::Quaterniond(Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitZ()))};
    };
    nlohmann::json script = nlohmann::json::array();
    const auto [start, o0] = along(0.0);
    script.push_back(pose(0.0, start + Eigen::Vector3d(0, 0, 45), o0)); // above, then down through the plate
    script.push_back(pose(0.4, start, o0));
    const int steps = 24;
    for (int k = 1; k <= steps; ++k) {
        const auto [p, o] = along(turn * k / steps);
        script.push_back(pose(0.4 + 1.2 * k / steps, p, o));
    }
    return parse(blade_scene(plate, 1e5, held, script, false, {8, 1, 30}), name);
}

inline void expect_one_sheet(const SheetCount& n)
{
    EXPECT_EQ(n.sheets, 1u);
    EXPECT_EQ(n.parallel_pairs, 0u);
    EXPECT_EQ(n.slivers, 0u);
}

/// The drooping slab (80 x 40 x 8 mm, held at one end) cut across by a blade turned 90 degrees
/// about z, then tilted by `tilt` radians about x, held still on it for half a second and drawn down.
inline io::Scene drooping_slab(double tilt, double x_mm, double youngs_pa, const std::string& name)
{
    const Eigen::Quaterniond o = Eigen::AngleAxisd(tilt, Eigen::Vector3d::UnitX()) * Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ());
    const nlohmann::json slab = {{"phantom", {{"shape", "beam"}, {"size_mm", {80, 40, 8}}, {"voxel_mm", 1.0}}}, {"levels", 2}};
    return parse(blade_scene(slab, youngs_pa, {{{"type", "fixed"}, {"box_mm", {{-1, -1, -1}, {3, 41, 9}}}}},
                             {pose(0.0, {x_mm, 20, 40}, o), pose(0.5, {x_mm, 20, 40}, o), pose(1.5, {x_mm, 20, -60}, o)}),
                 name);
}

} // namespace vox::sim::test
