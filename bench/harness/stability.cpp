#include "bench/harness/stability.hpp"
#include "sim/dbg_method.hpp"
#include "sim/frame_loop.hpp"
#include "sim/dbg_simulation.hpp"

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "io/scene_object.hpp"

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <sstream>

namespace vox::bench {

using sim::DbgSimulation;
using sim::build_scene_grid;
namespace {

/// What a case changes: the scene document before it is read, the simulation before stepping,
/// and the solver between steps (step index given).
struct Case {
    std::string variation;
    std::function<void(nlohmann::json&)> edit_scene;        ///< may be empty
    std::function<void(DbgSimulation&)> perturb;          ///< may be empty
    std::function<void(DbgSimulation&, int)> before_step; ///< may be empty
};

struct Object {
    std::string name;
    nlohmann::json scene;
    double size_mm = 0.0;        ///< largest extent, for the "bounded" judgement
    Eigen::Vector3d axis_origin; ///< twist axis through this point along x, mm
    Eigen::Vector3d tip_box_lo, tip_box_hi; ///< where the 100 N force goes, mm
};

std::string number(double v)
{
    char text[32];
    std::snprintf(text, sizeof text, "%g", v);
    return text;
}

StabilityResult run_case(const Object& object, const Case& c, int steps)
{
    StabilityResult r;
    r.object = object.name;
    r.variation = c.variation;
    try {
        nlohmann::json document = object.scene;
        if (c.edit_scene) c.edit_scene(document);
        const io::Scene scene = io::parse_scene(document, std::filesystem::current_path(), object.name + " (" + c.variation + ")");
        auto labels = std::make_shared<const grid::LabelGrid>(io::build_scene_object(scene));
        // Stepped through the frame loop every command uses (no tools here), the branched grid's
        // own simulation perturbed and read between steps.
        sim::DbgMethod method(scene, labels, scene.object.levels, std::min(6, std::max(scene.object.levels, 1) + 3));
        sim::ToolPolicy tools(scene);
        sim::FrameLoop loop(scene, method, tools);
        DbgSimulation& sim = method.simulation();
        if (c.perturb) c.perturb(sim);
        const auto& rest = sim.model().rest_positions();
        const fem::ImplicitSolver& solver = sim.solver(); // read-only access keeps the solver's caches
        const auto& mass = sim.model().nodal_mass();
        const auto& floor = sim.model().added_mass();
        // Energy bound: kinetic plus elastic energy can never exceed the initial energy plus the
        // work the external forces (gravity, loads) have done; implicit Euler and damping only
        // take energy away. Anything above is energy the numerics made up.
        double budget = sim.solver().elastic_energy();
        const Eigen::Vector3d gravity = scene.gravity_m_s2;
        for (int k = 0; k < steps; ++k) {
            if (c.before_step) c.before_step(sim, k);
            const std::vector<Eigen::Vector3d> before = solver.positions();
            sim::StepFigures s;
            try {
                s = loop.next().step;
            } catch (const sim::Diverged& e) {
                r.outcome = "diverged";
                r.detail = e.what();
                return r;
            }
            for (std::size_t n = 0; n < rest.size(); ++n)
                budget += ((mass[n] - floor[n]) * gravity + sim.solver().external_forces()[n]).dot(solver.positions()[n] - before[n]);
            ++r.steps;
            r.unconverged_steps += !s.converged;
            r.projected_steps += s.energy_projected;
            r.final_kinetic_j = s.kinetic_energy_j;
            r.final_elastic_j = s.elastic_energy_j.value_or(0.0);
            r.peak_kinetic_j = std::max(r.peak_kinetic_j, s.kinetic_energy_j);
            r.max_stretch = std::max(r.max_stretch, s.max_stretch);
            double worst = 0.0;
            bool finite = std::isfinite(s.kinetic_energy_j) && std::isfinite(s.elastic_energy_j.value_or(0.0));
            for (std::size_t n = 0; n < rest.size(); ++n) {
                finite = finite && solver.positions()[n].allFinite();
                worst = std::max(worst, (solver.positions()[n] - rest[n]).norm() * 1e3);
            }
            r.max_displacement_mm = std::max(r.max_displacement_mm, worst);
            if (!finite) {
                r.outcome = "diverged";
                r.detail = "non-finite state at step " + std::to_string(k + 1);
                return r;
            }
            const double energy = s.kinetic_energy_j + s.elastic_energy_j.value_or(0.0);
            if (energy > 1.05 * budget + 1e-12) {
                r.outcome = "diverged";
                r.detail = "energy " + number(energy) + " J exceeds the " + number(budget) + " J put in, at step " + std::to_string(k + 1);
                return r;
            }
        }
        r.outcome = "stable";
        if (r.max_displacement_mm > object.size_mm)
            r.detail = "moved further than the object is long (" + number(r.max_displacement_mm) + " mm): physical for this load, "
                       "but no longer a small-strain regime";
        if (r.unconverged_steps)
            r.detail += std::string(r.detail.empty() ? "" : "; ") + std::to_string(r.unconverged_steps) +
                        " steps stopped at the CG iteration cap";
        if (r.projected_steps)
            r.detail += std::string(r.detail.empty() ? "" : "; ") + std::to_string(r.projected_steps) +
                        " steps created energy even solved fully at dt/32 and lost it again (energy projection)";
    } catch (const InputError& e) {
        r.outcome = "refused";
        r.detail = e.what();
    }
    return r;
}

std::vector<Case> cases(const Object& object)
{
    std::vector<Case> out;
    for (double nu : {0.0, 0.3, 0.45, 0.49, 0.499})
        out.push_back({"Poisson ratio " + number(nu), [nu](nlohmann::json& s) { s["materials"]["default"]["poisson_ratio"] = nu; }, {}, {}});
    for (double e : {1e2, 1e4, 1e6, 1e9, 1e10})
        out.push_back({"Young's modulus " + number(e) + " Pa", [e](nlohmann::json& s) { s["materials"]["default"]["youngs_modulus_pa"] = e; }, {}, {}});
    for (double dt : {1e-4, 1e-3, 1e-2, 1e-1})
        out.push_back({"dt " + number(dt) + " s", [dt](nlohmann::json& s) { s["solver"]["dt_s"] = dt; }, {}, {}});
    const Eigen::Vector3d origin = object.axis_origin;
    const double length = object.size_mm;
    out.push_back({"90-degree twist, released", {}, [origin, length](DbgSimulation& sim) {
                       // Every node turned about the long (x) axis by 90 degrees times x / length.
                       for (std::size_t n = 0; n < sim.model().node_count(); ++n) {
                           const Eigen::Vector3d p = sim.model().rest_positions()[n] * 1e3 - origin;
                           const double angle = 0.5 * M_PI * std::clamp(p.x() / length, 0.0, 1.0);
                           sim.solver().positions()[n] = (origin + Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitX()) * p) * 1e-3;
                       }
                   }, {}});
    out.push_back({"inverted (mirrored through its mid-plane)", {}, [origin](DbgSimulation& sim) {
                       for (std::size_t n = 0; n < sim.model().node_count(); ++n) {
                           Eigen::Vector3d& x = sim.solver().positions()[n];
                           x.z() = 2 * origin.z() * 1e-3 - x.z();
                       }
                   }, {}});
    // The scene's own load mechanism spreads the force over the nodes in the box; after the first
    // step it is taken away again.
    const Eigen::Vector3d lo = object.tip_box_lo, hi = object.tip_box_hi;
    // A hand slamming a device: 100 N and 1,000 N for one step, on the FEM and on the third method
    // (docs/shape-matching.md), whose paper claims stability under impulse-like input.
    for (const bool shape_matching : {false, true})
        for (double force : {100.0, 1000.0})
            out.push_back({number(force) + " N on the free end for one step" + (shape_matching ? ", shape matching" : ""),
                           [lo, hi, force, shape_matching](nlohmann::json& s) {
                               s["loads"] = {{{"box_mm", {{lo.x(), lo.y(), lo.z()}, {hi.x(), hi.y(), hi.z()}}}, {"force_n", {0, 0, -force}}}};
                               if (shape_matching) s["solver"]["type"] = "shape_matching";
                           },
                           {},
                           [](DbgSimulation& sim, int step) {
                               if (step == 1)
                                   for (Eigen::Vector3d& f : sim.solver().external_forces()) f.setZero();
                           }});
    return out;
}

nlohmann::json base_scene(nlohmann::json object, int level, const nlohmann::json& held_box)
{
    object["levels"] = level;
    return {{"object", object},
            {"materials", {{"default", {{"youngs_modulus_pa", 3e4}, {"poisson_ratio", 0.45}, {"density_kg_m3", 1000}}}}},
            {"solver", {{"dt_s", 0.01}, {"cg_max_iterations", 300}}},
            {"gravity_m_s2", {0, 0, -9.81}},
            {"constraints", {{{"type", "fixed"}, {"box_mm", held_box}}}}};
}

} // namespace

std::vector<StabilityResult> run_stability(bool quick)
{
    std::vector<Object> objects;
    const double beam_length = quick ? 40.0 : 200.0;
    objects.push_back({"beam " + number(beam_length) + " x 10 x 10 mm, level 1",
                       base_scene({{"phantom", {{"shape", "beam"}, {"size_mm", {beam_length, 10, 10}}}}}, 1,
                                  {{-1e3, -1e3, -1e3}, {0, 1e3, 1e3}}),
                       beam_length, {-0.5, 4.5, 4.5}, {beam_length - 2.5, -1e3, -1e3}, {1e3, 1e3, 1e3}});
    if (!quick) {
        nlohmann::json liver_object{{"volume", VOX_DATA_DIR "/liver.inr.gz"}, {"select", {{"label", {255}}}}};
        objects.push_back({"liver (label 255), level 4", base_scene(liver_object, 4, {{-1e4, -1e4, -1e4}, {1e4, 1e4, 60}}), 250.0,
                           {0, 120, 100}, {-1e4, -1e4, 150}, {1e4, 1e4, 1e4}});
    }
    std::vector<StabilityResult> results;
    const int steps = quick ? 10 : 40;
    for (const Object& o : objects)
        for (const Case& c : cases(o)) {
            log::info("bench stability: {}, {}", o.name, c.variation);
            results.push_back(run_case(o, c, steps));
        }
    // Fill 1/512: an 8^3-voxel block with one more voxel on its side, written as a small NRRD
    // scan: at level 3 (elements of 8^3 voxels) that voxel is alone in its element.
    const std::filesystem::path folder = std::filesystem::temp_directory_path() / ("voxsculpt-stability-" + std::to_string(::getpid()));
    std::filesystem::create_directories(folder);
    {
        std::ofstream nrrd(folder / "bump.nrrd", std::ios::binary);
        nrrd << "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 10 9 9\nspacings: 1 1 1\nencoding: raw\n\n";
        for (int z = 0; z < 9; ++z)
            for (int y = 0; y < 9; ++y)
                for (int x = 0; x < 10; ++x) nrrd.put(static_cast<char>((x < 8 && y < 8 && z < 8) || (x == 8 && y == 0 && z == 0) ? 1 : 0));
    }
    const Object bump{"8^3 block plus one voxel, level 3",
                      base_scene({{"volume", (folder / "bump.nrrd").string()}}, 3, {{-1e3, -1e3, -1e3}, {0.5, 1e3, 1e3}}), 9.0,
                      {0, 3.5, 3.5}, {7.5, -1e3, -1e3}, {1e3, 1e3, 1e3}};
    for (const Case& c : cases(bump)) {
        if (c.variation.find("Young") == std::string::npos && c.variation.find("dt") == std::string::npos &&
            c.variation.find(" N on the free end") == std::string::npos)
            continue; // the fill case is about conditioning: stiffness, time step and a kick
        log::info("bench stability: {}, {}", bump.name, c.variation);
        results.push_back(run_case(bump, c, steps));
        results.back().variation = "fill 1/512, " + results.back().variation;
    }
    std::filesystem::remove_all(folder);
    if (!quick) {
        // A CT's bone: anisotropic voxels (0.9 x 0.9 x 1.5 mm), the skull held at its base, and 24
        // loose fragments (and the holder's free part) falling as stiff free pieces.
        nlohmann::json skull_object{{"volume", VOX_DATA_DIR "/skull_phantom.nii.gz"},
                                    {"select", {{"threshold", {226, 3071}}}},
                                    {"unheld_pieces", "fall"}};
        const Object skull{"skull phantom, bone with its 24 loose fragments falling, level 3",
                           base_scene(skull_object, 3, {{0, 0, 0}, {180, 216, 14}}), 105.0,
                           {90, 110, 10}, {80, 100, 106}, {100, 120, 120}};
        for (const Case& c : cases(skull)) {
            if (c.variation.find("Young") == std::string::npos && c.variation.find("dt") == std::string::npos &&
                c.variation.find(" N on the free end") == std::string::npos)
                continue; // stiffness, time step and a kick on loose stiff pieces
            log::info("bench stability: {}, {}", skull.name, c.variation);
            results.push_back(run_case(skull, c, steps));
        }
    }
    return results;
}

void write_stability(const std::filesystem::path& dir, const std::vector<StabilityResult>& results)
{
    std::ostringstream md;
    md << "# Stability at the extremes (`voxsculpt bench stability`)\n\n"
          "Each case steps a scene (dynamic, dt 0.01 s unless varied, E 30 kPa, nu 0.45, 1000 kg/m^3, "
          "Rayleigh 0.5 / 0.002, gravity -z, one end or the bottom held) and is judged: *stable* when "
          "every number stays finite and kinetic plus elastic energy never exceeds the initial energy plus "
          "the work of gravity and loads by more than 5 %; *refused* when the solver stops it with a "
          "message (a step that still creates energy at 1/32 of dt); *diverged* otherwise. Large "
          "displacements of soft objects under gravity are physical, noted, and not failures.\n\n";
    md << "| object | case | outcome | steps | max displacement (mm) | max stretch | peak / final kinetic energy (J) | final elastic energy (J) | note |\n"
          "|---|---|---|---|---|---|---|---|---|\n";
    nlohmann::json j = nlohmann::json::array();
    for (const StabilityResult& r : results) {
        char line[512];
        std::snprintf(line, sizeof line, "| %s | %s | %s | %d | %.3g | %.3g | %.3g / %.3g | %.3g | %s |\n", r.object.c_str(), r.variation.c_str(),
                      r.outcome.c_str(), r.steps, r.max_displacement_mm, r.max_stretch, r.peak_kinetic_j, r.final_kinetic_j, r.final_elastic_j,
                      r.detail.c_str());
        md << line;
        j.push_back({{"object", r.object}, {"case", r.variation}, {"outcome", r.outcome}, {"detail", r.detail}, {"steps", r.steps},
                     {"max_displacement_mm", r.max_displacement_mm}, {"max_stretch", r.max_stretch}, {"peak_kinetic_j", r.peak_kinetic_j},
                     {"final_kinetic_j", r.final_kinetic_j}, {"final_elastic_j", r.final_elastic_j},
                     {"unconverged_steps", r.unconverged_steps}, {"projected_steps", r.projected_steps}});
    }
    std::filesystem::create_directories(dir);
    write_atomically(dir / "stability.md", [&](const std::filesystem::path& tmp) { std::ofstream(tmp) << md.str(); });
    write_atomically(dir / "stability.json", [&](const std::filesystem::path& tmp) { std::ofstream(tmp) << j.dump(1) << '\n'; });
    std::printf("%s\nwrote %s and %s\n", md.str().c_str(), (dir / "stability.md").c_str(), (dir / "stability.json").c_str());
}

} // namespace vox::bench
