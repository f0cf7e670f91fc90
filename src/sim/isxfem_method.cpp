#include "sim/isxfem_method.hpp"

#include "sim/isxfem_fem_mesh.hpp"

#include "core/error.hpp"
#include "core/log.hpp"
#include "core/stopwatch.hpp"
#include "core/union_find.hpp"
#include "sim/dbg_simulation.hpp"
#include "fem/element_shapes.hpp"

#include <cstdint>
#include <cstdio>
#include <iterator>
#include <utility>

namespace vox::sim {
namespace {

/// A blade's thickness: crack walls still closer together than this are left out of its contact
/// (walls lying on each other would close on it from both sides at once, which only stiffens the
/// solve and shakes a haptic tool); other tools touch every wall.
double closed_walls_mm(const io::ToolSpec& spec) { return spec.action == io::ToolAction::cut ? spec.size_mm.y() : 0.0; }

} // namespace

void check_isxfem_scene(const io::Scene& scene)
{
    if (scene.object.auto_levels) throw scene.error("object.levels", "\"isxfem\" needs a fixed level (0 to 6), not \"auto\"");
    if (scene.object.smooth_surface.value_or(false))
        throw scene.error("object.smooth_surface", "\"isxfem\" closes its cracks on the voxel surface and does not smooth "
                                                   "it yet; smoothing needs \"type\": \"dbg\"");
    if (scene.object.unheld == io::UnheldPieces::rigid)
        throw scene.error("object.unheld_pieces", "\"isxfem\" does not move pieces as rigid bodies yet; \"rigid\" needs \"type\": \"dbg\"");
    for (std::size_t k = 0; k < scene.tools.size(); ++k) {
        const io::ToolSpec& t = scene.tools[k];
        const std::string where = "tools[" + std::to_string(k) + "]";
        if (t.action == io::ToolAction::wet)
            throw scene.error(where, "\"" + t.name + "\": \"isxfem\" does not wet yet; wetting tools need \"type\": \"dbg\"");
        if (t.action == io::ToolAction::drill)
            throw scene.error(where, "\"" + t.name + "\": \"isxfem\" does not remove material, so it cannot drill; drills need \"type\": \"dbg\"");
        if (t.action != io::ToolAction::cut) continue;
        if (t.shape != io::ToolShape::blade && t.shape != io::ToolShape::scalpel)
            throw scene.error(where, "\"" + t.name + "\": \"isxfem\" cuts with blades and scalpels only so far; other cutting shapes need \"type\": \"dbg\"");
        if (t.cut_mode == io::CutMode::remove)
            throw scene.error(where + ".cut_mode", "\"" + t.name + "\": \"isxfem\" cuts without removing material (\"separate\", its default); "
                                                   "removing needs \"type\": \"dbg\"");
    }
}

IsxfemMethod::IsxfemMethod(const io::Scene& scene, std::shared_ptr<const grid::LabelGrid> labels, int level)
    : m_scene(scene), m_labels(std::move(labels)), m_level(level)
{
    check_isxfem_scene(scene);
    m_grid = std::make_unique<grid::BranchedGrid>(build_scene_grid(scene, *m_labels, std::max(level, 1)));
    m_obstacles = make_obstacles(m_scene);
    m_anchors.resize(m_obstacles.size());
    m_sim = std::make_unique<IsxfemSimulation>(m_scene, *m_grid, level);
    if (m_sim->held_piece_count() > 0)
        log::info("{}: {} piece(s) held by no constraint stay where they are (object.unheld_pieces \"hold\"; "
                  "\"fall\" frees them, \"leave_out\" drops them)", m_scene.source, m_sim->held_piece_count());
    m_strokes.resize(scene.tools.size());
}

IsxfemMethod::~IsxfemMethod() = default;

std::string IsxfemMethod::linear_solver() const
{
    const isxfem::XfemSolver& s = m_sim->solver();
    return s.fallback_note().empty() ? std::string("CG, ") + s.preconditioner_name() + " preconditioner" : s.fallback_note();
}

std::string IsxfemMethod::description() const
{
    char text[256];
    std::snprintf(text, sizeof text, "Is-XFEM (k = %g), level %d, %zu tetrahedra, %zu degrees of freedom", m_scene.solver.isxfem_k, m_level,
                  element_count(), dof_count());
    return text;
}

void IsxfemMethod::begin_tools(std::size_t tool_count)
{
    m_contact.resize(tool_count);
    m_loads.clear();
    m_cuts_known.clear();
    m_frame_cut = {};
    ++m_frame;
}

const contact::ContactResult& IsxfemMethod::touch(std::size_t tool, const io::ToolSpec& spec, const contact::PlacedShape& at,
                                                  const contact::PlacedShape* from)
{
    IsxfemSimulation::Touch t = m_sim->touch(at, {spec.push_margin_mm, spec.contact_stiffness_n_per_mm}, from, closed_walls_mm(spec));
    for (const isxfem::PointLoad& l : t.loads) m_cuts_known.push_back(m_sim->model().elements()[l.tet].cuts.size());
    m_loads.insert(m_loads.end(), t.loads.begin(), t.loads.end());
    m_contact[tool] = std::move(t.contact);
    return m_contact[tool];
}

CutFigures IsxfemMethod::follow(std::size_t tool, const io::ToolSpec& spec, const io::ToolPose& from, const contact::PlacedShape& at,
                                const CutOrder& order)
{
    // Blades and scalpels cut (check_isxfem_scene; the viewer may turn another tool to cutting:
    // it only pushes then).
    if (spec.shape != io::ToolShape::blade && spec.shape != io::ToolShape::scalpel) return {};
    if (!m_strokes[tool]) m_strokes[tool].emplace(spec);
    BladeStroke& stroke = *m_strokes[tool];
    // Not touching, the stroke waits: a blade that stays in its plane goes on with the same crack
    // when it touches again (a drooping slab swinging away from a blade and back made a second
    // crack beside the first). It ends when the tool leaves the scene (lift), turns or moves off
    // its plane.
    if (!order.touching) return {};
    // Marking, the stroke counts from the first touch (the object is held, so the material around
    // the blade has not moved since); otherwise it goes on through every frame the blade touches,
    // one crack, and cuts what the frames whose pressure held swept.
    io::ToolPose to;
    to.placed = true;
    to.position_mm = at.position;
    to.orientation = at.orientation;
    const isxfem::CutReport r = stroke.advance(*m_sim, from, to, m_sim->mean_displacement_mm(at.world_bounds(spec.push_margin_mm)),
                                                   order.cut       ? BladeStroke::Sweep::cut
                                                   : order.marking ? BladeStroke::Sweep::mark
                                                                   : BladeStroke::Sweep::pass);
    m_frame_cut.cut_tets += r.cut_tets;
    m_frame_cut.new_blocks += r.new_blocks;
    m_frame_cut.partial_tets += r.partial_tets;
    m_frame_cut.already_cut += r.already_cut;
    m_frame_cut.beside_earlier += r.beside_earlier;
    m_frame_cut.recut_tets += r.recut_tets;
    m_frame_cut.crossed_tets += r.crossed_tets;
    CutFigures out;
    out.cut_elements = r.cut_tets;
    if (r.cut_tets > 0) { // the surface closed along the new crack now, as the branched grid remeshes in its cut
        Stopwatch clock;
        (void)m_sim->closure_counts();
        out.remesh_ms = clock.lap();
    }
    return out;
}

void IsxfemMethod::lift(std::size_t tool)
{
    if (m_strokes[tool]) m_strokes[tool]->end();
}

void IsxfemMethod::wet(std::size_t, double)
{
    // Refused with the scene (check_isxfem_scene): nothing to do.
}

void IsxfemMethod::end_tools()
{
    // A cut this frame may have cut a loaded point's tetrahedron: the point acts on its own side of
    // the new cut, and keeps its sides of the earlier ones (cuts are appended; a point on an earlier
    // crack's face knows its side, which rounding at the plane would not).
    if (m_frame_cut.cut_tets > 0)
        for (std::size_t i = 0; i < m_loads.size(); ++i) {
            const unsigned known = (1u << m_cuts_known[i]) - 1u;
            const unsigned now = static_cast<unsigned>(m_sim->side_of(m_loads[i].tet, m_loads[i].bary));
            m_loads[i].side = static_cast<int>((static_cast<unsigned>(m_loads[i].side) & known) | (now & ~known));
        }
    // The obstacles press on the surface as the frame's cuts left it (their loads know every cut).
    // Obstacles and pieces push along their normals as pair contacts, the obstacles' first.
    const double voxel_mm = 1e3 * m_grid->voxels().voxel_size_m().maxCoeff();
    std::vector<isxfem::PointLoad> loads = m_loads;
    std::vector<fem::PairContact> pairs;
    m_obstacle_force.setZero();
    for (std::size_t k = 0; k < m_obstacles.size(); ++k) {
        // Points arriving from within two voxels are caught (faster ones a step late).
        IsxfemSimulation::ObstacleTouch t =
            m_sim->touch_obstacle(m_obstacles[k], m_scene.solver.dt_s, m_anchors[k], obstacle_skin_mm(voxel_mm), 2.0 * voxel_mm);
        m_obstacle_force += friction_force_n(t.contact); // the push: after the step
        loads.insert(loads.end(), t.loads.begin(), t.loads.end());
        std::move(t.pairs.begin(), t.pairs.end(), std::back_inserter(pairs));
    }
    m_obstacle_pairs = pairs.size();
    m_sim->solver().set_point_loads(std::move(loads));
    m_piece_contact = {};
    if (m_scene.piece_contact.enabled) {
        Stopwatch clock;
        IsxfemSimulation::PieceTouch t = m_sim->touch_pieces(m_scene.solver.dt_s, piece_contact_parameters(m_scene, voxel_mm));
        m_piece_contact = {true, t.faces.size() + t.edges.size(), t.edges.size(), t.vertices, 0.0, 0.0, deepest_mm(t.faces, t.edges)}; // force_n: after the step
        std::move(t.pairs.begin(), t.pairs.end(), std::back_inserter(pairs));
        m_piece_contact.ms = clock.lap();
    }
    m_sim->solver().set_pair_contact(std::move(pairs));
    // The run's counts, and what the user is told once.
    const isxfem::CutReport& c = m_frame_cut;
    if (c.crossed_tets > 0 && m_crossed == 0)
        log::warn("frame {}: two cuts cross inside {} tetrahedra; the added enrichments cannot move their four pieces apart "
                  "independently, so the pieces stay coupled there (counted per frame in stats.json: isxfem.crossed_tets; "
                  "orange in the pictures of --render-every)",
                  m_frame, c.crossed_tets);
    if (c.already_cut > 0 && m_frames_left_whole == 0)
        log::warn("frame {}: {} tetrahedra already cut twice were crossed by another cut and left as they were (Is-XFEM "
                  "takes two cuts per tetrahedron; their pieces stay joined along the new cut; orange in the pictures "
                  "of --render-every)",
                  m_frame, c.already_cut);
    m_cut_tets += c.cut_tets;
    m_recut += c.recut_tets;
    m_crossed += c.crossed_tets;
    m_beside += c.beside_earlier;
    m_frames_left_whole += c.already_cut > 0;
}

StepFigures IsxfemMethod::step()
{
    const isxfem::XfemStepStats s = m_sim->solver().step();
    m_obstacle_force += m_sim->solver().pair_contact_force(0, m_obstacle_pairs).vector_n;
    if (m_piece_contact.enabled) m_piece_contact.force_n = m_sim->solver().pair_contact_force(m_obstacle_pairs, SIZE_MAX).magnitude_n;
    StepFigures out;
    out.step_ms = s.step_ms;
    out.assembly_ms = s.assembly_ms;
    out.solve_ms = s.solve_ms;
    out.cg_iterations = s.cg_iterations;
    out.newton_iterations = 1;
    out.residual = s.residual;
    out.converged = s.converged;
    out.preconditioner_fallback = newly_failed(m_sim->solver().fallback_note(), m_fallback_reported);
    out.kinetic_energy_j = s.kinetic_energy_j;
    // Uncut tetrahedra by their nodes; a cut one's nodes need not bound either side (the
    // enrichment moves the sides apart), so it is left out.
    const auto& x = m_sim->solver().state();
    fem::ElementShapes shapes;
    for (const isxfem::XfemElement& el : m_sim->model().elements()) {
        if (el.is_cut()) continue;
        Eigen::Matrix3d f = Eigen::Matrix3d::Zero();
        Eigen::Vector3d middle = Eigen::Vector3d::Zero();
        for (std::size_t c = 0; c < 4; ++c) {
            f += x[el.node[c]] * el.geometry.gradient.row(static_cast<Eigen::Index>(c));
            middle += x[el.node[c]] / 4.0;
        }
        shapes.add(f, 1.0, middle);
    }
    out.inverted_elements = shapes.inverted;
    out.max_stretch = shapes.max_stretch;
    out.most_stretched_mm = {1e3 * shapes.most_stretched_m.x(), 1e3 * shapes.most_stretched_m.y(), 1e3 * shapes.most_stretched_m.z()};
    return out;
}

std::vector<SurfaceMark> IsxfemMethod::surface_marks() const
{
    std::vector<SurfaceMark> out;
    for (const IsxfemSimulation::Mark m : m_sim->surface_marks())
        out.push_back(m == IsxfemSimulation::Mark::coupled ? SurfaceMark::coupled
                      : m == IsxfemSimulation::Mark::cut   ? SurfaceMark::cut
                                                           : SurfaceMark::surface);
    return out;
}

std::vector<float> IsxfemMethod::surface_wetness() const { return std::vector<float>(m_sim->surface_vertex_count(), 0.0f); }

std::vector<Eigen::Vector3d> IsxfemMethod::surface_displacements_mm() const
{
    std::vector<Eigen::Vector3d> u = m_sim->surface_displacements();
    for (Eigen::Vector3d& d : u) d *= 1e3;
    return u;
}

void IsxfemMethod::sample_surface(const Eigen::AlignedBox3d& box, const io::ToolSpec& tool, contact::SurfacePoints& out) const
{
    m_sim->sample_surface(box, out, closed_walls_mm(tool));
}

std::size_t IsxfemMethod::piece_count() const
{
    // The closed surface's connected parts: each separate piece is closed on its own.
    const surface::SurfaceMesh m = m_sim->surface_mesh();
    UnionFind parts(m.positions.size());
    for (const Eigen::Vector3i& t : m.triangles) {
        parts.unite(static_cast<std::uint32_t>(t[0]), static_cast<std::uint32_t>(t[1]));
        parts.unite(static_cast<std::uint32_t>(t[0]), static_cast<std::uint32_t>(t[2]));
    }
    std::vector<unsigned char> root(m.positions.size(), 0);
    std::size_t n = 0;
    for (const Eigen::Vector3i& t : m.triangles) {
        const std::uint32_t r = parts.find(static_cast<std::uint32_t>(t[0]));
        n += root[r] == 0;
        root[r] = 1;
    }
    return n;
}

void IsxfemMethod::add_frame_figures(nlohmann::json& frame) const
{
    const isxfem::CutReport& c = m_frame_cut;
    frame["isxfem"] = {{"cut_tets", c.cut_tets},
                       {"partly_crossed_tets", c.partial_tets},
                       {"recut_tets", c.recut_tets},
                       {"crossed_tets", c.crossed_tets},
                       {"recut_tets_left", c.already_cut},
                       {"beside_earlier_cut_tets", c.beside_earlier},
                       {"regularised_blocks", m_sim->solver().regularised_blocks()}};
}

void IsxfemMethod::add_summary_figures(nlohmann::json& summary) const
{
    const isxfem::ClosureCounts closure = m_sim->closure_counts();
    if (closure.open_chains > 0)
        log::warn("{} run(s) of the cut surface could not be closed along their crack: the exported surface has holes there", closure.open_chains);
    summary["voxels"] = m_grid->voxels().alive_count();
    summary["mass_kg"] = m_grid->total_mass_kg();
    summary["held_pieces"] = m_sim->held_piece_count();
    summary["rigid_elements"] = m_sim->rigid_element_count();
    summary["rigid_bodies"] = 0; // Is-XFEM moves no piece as a rigid body
    summary["isxfem"] = {{"k", m_scene.solver.isxfem_k},
                         {"regularisation", {{"lambda", m_scene.solver.isxfem_regularisation_lambda},
                                             {"threshold", m_scene.solver.isxfem_regularisation_threshold}}},
                         {"cut_tets", m_cut_tets},
                         {"cuts", m_sim->model().cut_count()},
                         {"partly_crossed_tets_last_frame", m_frame_cut.partial_tets},
                         {"recut_tets", m_recut},
                         {"crossed_tets", m_crossed},
                         {"beside_earlier_cut_tets", m_beside},
                         {"frames_with_recut_tets_left", m_frames_left_whole},
                         {"crack_faces", closure.faces},
                         {"slit_faces", closure.slit_faces},
                         {"open_crack_chains", closure.open_chains}};
}

std::unique_ptr<Method> IsxfemMethod::at_level(int level) const { return std::make_unique<IsxfemMethod>(m_scene, m_labels, level); }

namespace {

struct IsxfemCheckpoint final : Checkpoint {
    explicit IsxfemCheckpoint(IsxfemSimulation::State s) : state(std::move(s)) {}
    IsxfemSimulation::State state;
    std::size_t cut_tets = 0, recut = 0, crossed = 0, beside = 0, frames_left_whole = 0;
};

} // namespace

std::size_t IsxfemMethod::cut_count() const { return m_sim->cut_log().size(); }

nlohmann::json IsxfemMethod::cuts_since(std::size_t from) const
{
    const auto vec = [](const Eigen::Vector3d& v) { return nlohmann::json{v.x(), v.y(), v.z()}; };
    nlohmann::json out = nlohmann::json::array();
    const auto& log = m_sim->cut_log();
    for (std::size_t c = from; c < log.size(); ++c) {
        nlohmann::json patches = nlohmann::json::array();
        for (const isxfem::CutPatch& p : log[c].patches) {
            nlohmann::json corners = nlohmann::json::array();
            for (const Eigen::Vector3d& x : p.corners) corners.push_back(vec(x));
            patches.push_back({{"normal", vec(p.normal)}, {"corners", std::move(corners)}});
        }
        out.push_back({{"extend", log[c].extend}, {"new_from", log[c].new_from}, {"patches", std::move(patches)}});
    }
    return out;
}

void IsxfemMethod::replay_cuts(const nlohmann::json& cuts)
{
    // A journal may be damaged: its types are checked here, its geometry by the simulation.
    const auto vec = [](const nlohmann::json& a) {
        if (!a.is_array() || a.size() != 3 || !a[0].is_number() || !a[1].is_number() || !a[2].is_number())
            throw InputError("expected an array of 3 numbers");
        return Eigen::Vector3d(a[0].get<double>(), a[1].get<double>(), a[2].get<double>());
    };
    if (!cuts.is_array()) throw InputError("the cuts are not an array");
    std::size_t cut_tets = 0;
    for (std::size_t c = 0; c < cuts.size(); ++c) {
        const nlohmann::json& j = cuts[c];
        try {
            if (!j.is_object() || !j.contains("extend") || !j["extend"].is_number_integer() || !j.contains("new_from") ||
                !j["new_from"].is_number_unsigned() || !j.contains("patches") || !j["patches"].is_array())
                throw InputError("expected {\"extend\": integer, \"new_from\": count, \"patches\": [...]}");
            IsxfemSimulation::CutCall call;
            call.extend = j["extend"].get<int>();
            call.new_from = j["new_from"].get<std::size_t>();
            for (const auto& p : j["patches"]) {
                if (!p.is_object() || !p.contains("normal") || !p.contains("corners") || !p["corners"].is_array())
                    throw InputError("a patch is {\"normal\": [x, y, z], \"corners\": [[x, y, z], ...]}");
                isxfem::CutPatch patch;
                patch.normal = vec(p["normal"]);
                for (const auto& x : p["corners"]) patch.corners.push_back(vec(x));
                call.patches.push_back(std::move(patch));
            }
            cut_tets += m_sim->replay(call).cut_tets;
        } catch (const InputError& e) {
            throw InputError("cut " + std::to_string(c) + ": " + e.what());
        }
    }
    m_cut_tets += cut_tets;
}

std::vector<double> IsxfemMethod::motion() const
{
    const isxfem::XfemSolver& solver = std::as_const(*m_sim).solver();
    std::vector<double> out;
    for (const std::vector<Eigen::Vector3d>* field : {&solver.state(), &solver.velocities()})
        for (const Eigen::Vector3d& p : *field) out.insert(out.end(), p.data(), p.data() + 3);
    return out;
}

void IsxfemMethod::set_motion(const std::vector<double>& numbers)
{
    const std::size_t blocks = m_sim->solver().state().size();
    check_motion(numbers, 6 * blocks);
    std::vector<Eigen::Vector3d> x(blocks), v(blocks);
    for (std::size_t b = 0; b < blocks; ++b) {
        x[b] = Eigen::Vector3d(numbers[3 * b], numbers[3 * b + 1], numbers[3 * b + 2]);
        v[b] = Eigen::Vector3d(numbers[3 * (blocks + b)], numbers[3 * (blocks + b) + 1], numbers[3 * (blocks + b) + 2]);
    }
    m_sim->solver().set_state(std::move(x), std::move(v));
}

std::unique_ptr<Checkpoint> IsxfemMethod::checkpoint() const
{
    auto c = std::make_unique<IsxfemCheckpoint>(m_sim->state());
    c->cut_tets = m_cut_tets;
    c->recut = m_recut;
    c->crossed = m_crossed;
    c->beside = m_beside;
    c->frames_left_whole = m_frames_left_whole;
    return c;
}

void IsxfemMethod::restore(const Checkpoint& checkpoint)
{
    const auto& c = dynamic_cast<const IsxfemCheckpoint&>(checkpoint);
    m_sim->restore(c.state);
    for (auto& stroke : m_strokes) // their cuts may be gone: the next touch begins anew
        if (stroke) stroke->end();
    m_cut_tets = c.cut_tets;
    m_recut = c.recut;
    m_crossed = c.crossed;
    m_beside = c.beside;
    m_frames_left_whole = c.frames_left_whole;
    m_loads.clear();
    m_cuts_known.clear();
}

std::optional<io::VtuMesh> IsxfemMethod::fem_mesh() const { return isxfem_fem_mesh(*m_sim, *m_labels, m_level); }

} // namespace vox::sim
