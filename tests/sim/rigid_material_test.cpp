// Rigid material ("rigid": true) and "unheld_pieces": "rigid": bone holds the soft tissue attached
// to it exactly as a constraint on the same nodes would; a rigid fragment nothing holds stays put
// by default and falls as implicit Euler's free fall under "fall", without deforming; a pushed
// rigid piece moves and turns without changing shape; a held rigid object leaves no degree of
// freedom; Is-XFEM holds rigid material and refuses what it cannot do, by name.

#include "core/error.hpp"
#include "grid/label_grid.hpp"
#include "io/scene.hpp"
#include "io/scene_object.hpp"
#include "sim/frame_loop.hpp"
#include "sim/method_factory.hpp"
#include "sim/tool_policy.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>

namespace fs = std::filesystem;

namespace vox::sim {
namespace {

/// 1 mm voxels (voxel i spans i - 0.5 .. i + 0.5 mm), indices y and z 0..3: bone (label 1) x 0..7,
/// soft tissue (label 2) x 8..31 attached to it, and a loose bone fragment (label 1) x 40..43.
fs::path bone_and_tissue()
{
    const fs::path path = fs::path(::testing::TempDir()) / "bone_and_tissue.vdb";
    grid::LabelGrid g;
    for (int k = 0; k < 4; ++k)
        for (int j = 0; j < 4; ++j) {
            for (int i = 0; i < 8; ++i) g.set({i, j, k}, 1);
            for (int i = 8; i < 32; ++i) g.set({i, j, k}, 2);
            for (int i = 40; i < 44; ++i) g.set({i, j, k}, 1);
        }
    g.save(path);
    return path;
}

nlohmann::json base(bool bone_rigid, const char* type = "dbg")
{
    nlohmann::json bone = {{"youngs_modulus_pa", 1.5e10}, {"poisson_ratio", 0.3}, {"density_kg_m3", 1900}};
    if (bone_rigid) bone["rigid"] = true;
    return {
        // Unsmoothed: a smoothed vertex may sit beside the element that moves it.
        {"object", {{"volume", bone_and_tissue().string()}, {"select", {{"label", {1, 2}}}}, {"levels", 1}, {"smooth_surface", false}}},
        {"materials", {{"labels", {{"1", bone}, {"2", {{"youngs_modulus_pa", 2e4}, {"poisson_ratio", 0.4}, {"density_kg_m3", 1000}}}}}}},
        {"solver", {{"type", type}, {"dt_s", 0.01}, {"rayleigh_mass_per_s", 1.0}}},
        {"gravity_m_s2", {0, 0, -9.81}},
    };
}

io::Scene parse(const nlohmann::json& doc) { return io::parse_scene(doc, ::testing::TempDir(), "rigid.json"); }

struct Outcome {
    surface::SurfaceMesh mesh;                ///< final positions, mm
    std::vector<Eigen::Vector3d> displacement; ///< per surface vertex, mm
    nlohmann::json summary;
    std::string linear_solver;
};

Outcome run(const io::Scene& scene, int frames)
{
    auto labels = std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene));
    std::unique_ptr<Method> method = open_method(scene, labels).method;
    ToolPolicy tools(scene);
    FrameLoop loop(scene, *method, tools);
    for (int f = 0; f < frames; ++f) loop.next();
    Outcome out{method->surface_mesh(), method->surface_displacements_mm(), nlohmann::json::object(), method->linear_solver()};
    method->add_summary_figures(out.summary);
    return out;
}

/// The rest position (mm) of surface vertex v.
Eigen::Vector3d rest(const Outcome& r, std::size_t v) { return r.mesh.positions[v].cast<double>() - r.displacement[v]; }

TEST(RigidMaterial, BoneHoldsTheSoftTissueAsAConstraintOnItsNodesWould)
{
    // Bone ends on a cell face at level 1, so its elements' nodes are the nodes x <= 7.5 mm: exactly
    // what a fixed box over x <= 8.5 mm holds when the bone is elastic.
    const Outcome rigid = run(parse(base(true)), 20);
    nlohmann::json held = base(false);
    held["constraints"] = {{{"type", "fixed"}, {"box_mm", {{-1, -1, -1}, {8.5, 5, 5}}}}};
    const Outcome constrained = run(parse(held), 20);
    ASSERT_EQ(rigid.displacement.size(), constrained.displacement.size());
    double sag = 0.0;
    for (std::size_t v = 0; v < rigid.displacement.size(); ++v) {
        if (rest(rigid, v).x() > 39.0) continue; // the loose fragment: held by default in both runs
        EXPECT_NEAR((rigid.displacement[v] - constrained.displacement[v]).norm(), 0.0, 1e-6) << "vertex " << v;
        if (rest(rigid, v).x() < 7.5) EXPECT_EQ(rigid.displacement[v].norm(), 0.0) << "bone moved at " << rest(rigid, v).transpose();
        sag = std::max(sag, -rigid.displacement[v].z());
    }
    EXPECT_GT(sag, 0.5) << "the soft tissue hangs from the bone";
    EXPECT_EQ(rigid.summary["rigid_bodies"], 0);
    EXPECT_EQ(rigid.summary["rigid_elements"], 4 * 2 * 2 + 2 * 2 * 2); // cells of bone and of the fragment, at level 1
    EXPECT_EQ(rigid.summary["held_pieces"], 1);                // the fragment, by "hold"
}

TEST(RigidMaterial, ALooseFragmentFallsWithoutDeformingUnderFall)
{
    nlohmann::json doc = base(true);
    doc["object"]["unheld_pieces"] = "fall";
    const io::Scene scene = parse(doc);
    const int frames = 10;
    const Outcome r = run(scene, frames);
    EXPECT_EQ(r.summary["rigid_bodies"], 1);
    // Implicit Euler with mass-proportional damping alpha: v' = (v + dt g) / (1 + alpha dt).
    const double dt = 0.01, alpha = 1.0, g = -9.81;
    double v = 0.0, z = 0.0;
    for (int f = 0; f < frames; ++f) {
        v = (v + dt * g) / (1.0 + alpha * dt);
        z += dt * v;
    }
    std::size_t fragment = 0;
    for (std::size_t i = 0; i < r.displacement.size(); ++i) {
        if (rest(r, i).x() < 39.0) continue;
        ++fragment;
        EXPECT_NEAR(r.displacement[i].z(), 1e3 * z, 1e-6) << "vertex " << i;
        EXPECT_NEAR(r.displacement[i].x(), 0.0, 1e-9);
        EXPECT_NEAR(r.displacement[i].y(), 0.0, 1e-9);
    }
    EXPECT_GT(fragment, 20u);
}

/// Two soft blocks under "unheld_pieces": "rigid", no gravity; a sphere pushes the loose one
/// (x 12..16) off its centre line, so it both moves and turns.
io::Scene pushed_piece()
{
    nlohmann::json doc = base(false);
    doc["object"]["unheld_pieces"] = "rigid";
    doc["gravity_m_s2"] = {0, 0, 0};
    doc["constraints"] = {{{"type", "fixed"}, {"box_mm", {{-1, -1, -1}, {0, 5, 5}}}}};
    doc["tools"] = {{{"name", "finger"}, {"shape", "sphere"}, {"radius_mm", 1.5}, {"contact_stiffness_n_per_mm", 5.0}}};
    doc["script"] = {{{"t_s", 0.0}, {"tool", "finger"}, {"position_mm", {48, 0.5, 2}}},
                     {{"t_s", 0.2}, {"tool", "finger"}, {"position_mm", {42.5, 0.5, 2}}}};
    return parse(doc);
}

TEST(UnheldPiecesRigid, APushedPieceMovesAndTurnsWithoutChangingShape)
{
    const Outcome r = run(pushed_piece(), 25);
    EXPECT_EQ(r.summary["rigid_bodies"], 1);
    std::vector<std::size_t> piece;
    double moved = 0.0;
    for (std::size_t i = 0; i < r.displacement.size(); ++i)
        if (rest(r, i).x() > 39.0) {
            piece.push_back(i);
            moved = std::max(moved, r.displacement[i].norm());
        }
    ASSERT_GT(piece.size(), 20u);
    EXPECT_GT(moved, 0.2) << "the tool pushed the piece";
    // Distances between its surface vertices are those at rest: it moved rigidly.
    double turn = 0.0;
    for (std::size_t a : piece)
        for (std::size_t b : piece) {
            const Eigen::Vector3d now = (r.mesh.positions[a] - r.mesh.positions[b]).cast<double>();
            const Eigen::Vector3d before = rest(r, a) - rest(r, b);
            EXPECT_NEAR(now.norm(), before.norm(), 1e-4); // mesh positions are floats
            if (before.norm() > 3.0) turn = std::max(turn, std::acos(std::clamp(now.normalized().dot(before.normalized()), -1.0, 1.0)));
        }
    EXPECT_GT(turn, 1e-3) << "pushed off its centre line, it turned";
}

TEST(RigidMaterial, AHeldRigidObjectLeavesNothingToSolve)
{
    nlohmann::json doc = base(true);
    doc["object"]["select"] = {{"label", {1}}};
    doc["materials"]["labels"].erase("2");
    const Outcome r = run(parse(doc), 3);
    EXPECT_EQ(r.linear_solver, "none: every node is held or rigid");
    for (const Eigen::Vector3d& d : r.displacement) EXPECT_EQ(d.norm(), 0.0);
}

TEST(RigidMaterial, IsRefusedWithPlasticityAndByIsxfemWhereItWouldMove)
{
    nlohmann::json plastic = base(true);
    plastic["materials"]["labels"]["1"]["plasticity"] = {{"yield_strain", 0.01}, {"creep_per_s", 1.0}, {"max_strain", 0.1}};
    EXPECT_THROW(parse(plastic), InputError);

    // Is-XFEM holds bone and the tissue on it as the branched grid does ...
    const Outcome held = run(parse(base(true, "isxfem")), 5);
    for (std::size_t v = 0; v < held.displacement.size(); ++v)
        if (rest(held, v).x() < 7.5) EXPECT_LT(held.displacement[v].norm(), 1e-12); // mm: rounding in the tetrahedra
    // ... and refuses, by name, a fragment that would have to move as a rigid body.
    nlohmann::json fall = base(true, "isxfem");
    fall["object"]["unheld_pieces"] = "fall";
    try {
        (void)run(parse(fall), 1);
        FAIL() << "accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("rigid body"), std::string::npos) << e.what();
    }
    nlohmann::json rigid = base(false, "isxfem");
    rigid["object"]["unheld_pieces"] = "rigid";
    EXPECT_THROW((void)run(parse(rigid), 1), InputError);
}

} // namespace
} // namespace vox::sim
