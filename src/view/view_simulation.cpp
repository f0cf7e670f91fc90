#include "view/view_simulation.hpp"

#include "core/error.hpp"
#include "core/log.hpp"
#include "haptics/force_devices.hpp"
#include "io/label_map_writer.hpp"
#include "io/mesh_writer.hpp"
#include "sim/dbg_method.hpp"
#include "sim/haptic_snapshot.hpp"
#include "view/scene_pictures.hpp"

#include <algorithm>
#include <map>
#include <stdexcept>

namespace vox::view {

ViewSimulation::ViewSimulation(io::Scene& scene, std::unique_ptr<sim::Method> method, sim::ToolPolicy& tools, ViewChannels& channels,
                               const ViewSimulationOptions& options)
    : m_scene(scene), m_method(std::move(method)), m_tools(tools), m_channels(channels), m_options(options),
      m_loop(scene, *m_method, tools), m_level(m_method->level())
{
    if (m_options.governor) {
        log::info("levels {} to {}: the session moves coarser when its frames miss {:g} ms for a second, and back when there is room",
                  m_options.governor->settings().finest, m_options.governor->settings().coarsest, m_options.governor->settings().budget_ms);
        m_loop.govern_levels(std::move(*m_options.governor));
        m_options.governor.reset();
    }
    if (options.hands.size() != channels.hands.size())
        throw std::logic_error("ViewSimulation: one hand per channel: " + std::to_string(options.hands.size()) + " against " +
                               std::to_string(channels.hands.size()));
    for (const ViewHand& h : options.hands) {
        Hand& hand = m_hands.emplace_back();
        hand.pose.shape = &tools.shape(h.tool);
        hand.pose.position = hand.heading = h.start_mm;
    }
    start_journal();
}

void ViewSimulation::start_journal()
{
    if (m_options.journal.empty()) return;
    m_journal.reset(); // closed before its file is set aside
    m_journal = std::make_unique<sim::JournalWriter>(m_options.journal, sim::journal_header(m_options.scene_file, *m_method), *m_method,
                                                     m_loop.frames(), m_loop.frames() * m_scene.solver.dt_s);
}

void ViewSimulation::resume_offered()
{
    if (!m_options.offered) return;
    if (m_method->cut_count() > 0) {
        log::info("J: the earlier session can be resumed only before the first cut (U undoes it)");
        return;
    }
    try {
        sim::resume(*m_method, *m_options.offered);
        let_go();
        m_history.clear();
        log::info("resumed the earlier session: {} stroke(s), {} cut(s)", m_options.offered->strokes.size(), m_method->cut_count());
        if (m_journal) m_journal->end_stroke(*m_method, m_loop.frames(), m_loop.frames() * m_scene.solver.dt_s);
    } catch (const InputError& e) {
        log::warn("not resumed: {}", e.what());
    }
    m_options.offered.reset();
}

void ViewSimulation::now_at_level(const std::string& why)
{
    const int from = m_level;
    m_level = m_method->level();
    start_journal(); // the journal holds one level's motion; the undo history carries its levels
    m_level_notice = "level " + std::to_string(from) + " -> " + std::to_string(m_level) + ": " + why;
    m_level_notice_until_s = m_now_s + 4.0;
}

void ViewSimulation::let_go()
{
    m_tools.reset();
    for (Hand& hand : m_hands) {
        if (hand.driven >= 0) m_tools.release(static_cast<std::size_t>(hand.driven));
        hand.driven = -1;
    }
}

void ViewSimulation::take_requests()
{
    ViewRequests& r = m_channels.requests;
    if (const int d = r.level_change.exchange(0); d != 0) {
        const int at = std::clamp(m_level + d, 1, m_options.grid_levels);
        if (at != m_level) {
            if (sim::LevelGovernor* g = m_loop.governor()) g->set_finest(at); // the user's level is the finest it returns to
            if (m_loop.move_to_level(at, "the level keys")) { // the state carried on (the branched grid)
                now_at_level("the level keys");
            } else { // Is-XFEM: its cracks live in one level's tetrahedra
                m_method = m_method->at_level(at);
                m_loop.set_method(*m_method);
                let_go();
                m_level = at;
                m_history.clear(); // the deformation restarts from rest at the new level
                start_journal();   // the journal holds one level's cuts
                log::info("level {}: {} elements (uncut: Is-XFEM cannot carry cuts across levels yet; the deformation from rest)", at,
                          m_method->element_count());
            }
        }
    }
    if (r.undo.exchange(false)) {
        if (m_history.undo(*m_method)) {
            let_go();
            log::info("undo: back to before the last stroke");
            if (m_method->level() != m_level) { // the stroke began at another level
                if (sim::LevelGovernor* g = m_loop.governor()) g->moved(m_level, m_method->level());
                now_at_level("undo");
            }
            if (m_journal) {
                m_journal->rewound(*m_method);
                m_journal->end_stroke(*m_method, m_loop.frames(), m_loop.frames() * m_scene.solver.dt_s);
            }
        } else {
            log::info("{}", m_method->checkpoint() ? "undo: nothing to undo" : "undo: not available with this method yet (docs/viewer.md)");
        }
    }
    if (r.resume.exchange(false)) resume_offered();
    io::ToolSpec& active = m_scene.tools[static_cast<std::size_t>(r.active.load())];
    if (const int a = r.set_action.exchange(-1); a >= 0)
        active.action = a == 0 ? io::ToolAction::push : a == 1 ? io::ToolAction::cut : io::ToolAction::wet;
    if (r.toggle_cut_mode.exchange(false)) {
        if (m_scene.solver.type == io::SolverType::isxfem) log::info("Is-XFEM cuts by separating only (it cannot remove material)");
        else active.cut_mode = active.cut_mode == io::CutMode::remove ? io::CutMode::separate : io::CutMode::remove;
    }
}

bool ViewSimulation::step(double now_s)
{
    ViewRequests& r = m_channels.requests;
    m_now_s = now_s;
    take_requests();
    if (r.paused.load() && !r.step_once.exchange(false)) return false;
    for (std::size_t d = 0; d < m_hands.size(); ++d) {
        Hand& hand = m_hands[d];
        HandChannel& channel = m_channels.hand(d);
        if (!channel.proxies.update()) continue;
        const ProxyPose& p = channel.proxies.read_slot();
        if (p.tool != hand.driven && hand.driven >= 0) m_tools.release(static_cast<std::size_t>(hand.driven));
        hand.driven = p.tool;
        hand.pose = p.pose;
        hand.heading = p.heading;
        hand.coupling_n_per_mm = p.coupling_n_per_mm;
        if (m_options.hands[d].arms) m_tools.arm(static_cast<std::size_t>(p.tool), (p.buttons & haptics::k_action_button) != 0);
    }
    watch_faults();
    // A stroke's checkpoint before any of its cuts: the window flags the stroke before it moves
    // the pointer, so a pose read above that belongs to the stroke sees the flag.
    if (r.stroke_started.exchange(false)) m_history.before_stroke(*m_method);
    for (const Hand& hand : m_hands)
        if (hand.driven >= 0)
            m_tools.drive(static_cast<std::size_t>(hand.driven), hand.pose.position, hand.pose.orientation, hand.heading, hand.coupling_n_per_mm);
    try {
        const sim::FrameStats frame = m_loop.next();
        for (std::size_t d = 0; d < m_hands.size(); ++d) // a tool that cut goes on cutting through
            if (m_hands[d].driven >= 0) m_channels.hand(d).passing.store(m_tools.passing(static_cast<std::size_t>(m_hands[d].driven)));
        if (frame.level_change) now_at_level(frame.level_change->reason);
        // A stroke ends when the button goes up, or (a 6-DoF controller) when a cut ends or the tool rests.
        const bool released = r.stroke_ended.exchange(false);
        if (m_stroke_ends.after_frame(frame) || released)
            if (m_journal) m_journal->end_stroke(*m_method, frame.frame, frame.t_s);
    } catch (const InputError& e) { // a step that cannot be trusted: said, and the session paused to keep it
        log::warn("{}; paused (SPACE runs on, U undoes the last stroke)", e.what());
        r.paused = true;
        if (m_journal) m_journal->end_stroke(*m_method, m_loop.frames(), m_loop.frames() * m_scene.solver.dt_s);
    }
    // For each device, the surface near its tool and where it is heading; and the simulation's
    // time for the scripted ones.
    for (std::size_t d = 0; d < m_hands.size(); ++d) {
        const Hand& hand = m_hands[d];
        HandChannel& channel = m_channels.hand(d);
        contact::SurfacePoints& out = channel.snapshots.write_slot();
        const std::size_t tool = hand.driven >= 0 ? static_cast<std::size_t>(hand.driven) : m_options.hands[d].tool;
        const io::ToolSpec& held = m_scene.tools[tool];
        Eigen::AlignedBox3d near = hand.pose.world_bounds(held.push_margin_mm + sim::k_snapshot_margin_mm);
        near.extend(contact::PlacedShape{hand.pose.shape, hand.heading, hand.pose.orientation}.world_bounds(held.push_margin_mm + sim::k_snapshot_margin_mm));
        sim::take_snapshot(*m_method, tool, held, hand.pose, near, now_s, out);
        channel.snapshots.publish();
    }
    m_channels.simulation_t_s.store(m_loop.frames() * m_scene.solver.dt_s, std::memory_order_relaxed);
    if (r.save_object.exchange(false)) save();
    if (r.picture_taken.exchange(false)) make_picture();
    r.frames.fetch_add(1, std::memory_order_relaxed);
    return true;
}

void ViewSimulation::watch_faults()
{
    std::string notice;
    for (const ViewHand& hand : m_options.hands) {
        if (!hand.watched) continue;
        const char* fault = hand.watched->fault();
        if (fault) {
            notice += (notice.empty() ? "" : "; ") + hand.watched->name() + ": " + fault;
            hand.watched->recover();
        }
    }
    if (!notice.empty()) notice += ": no force, the tool held where it was until the device answers";
    if (notice != m_fault_notice) {
        if (!notice.empty()) log::warn("{}", notice);
        else log::info("the devices answer again: their force ramps back in");
    }
    m_fault_notice = std::move(notice);
}

void ViewSimulation::save() const
{
    try {
        const std::filesystem::path& dir = m_options.out_dir;
        const surface::SurfaceMesh m = m_method->surface_mesh();
        for (const char* name : {"view_surface.obj", "view_surface.ply", "view_surface.stl"})
            io::write_mesh((dir / name).string(), m.positions, m.triangles, m.labels);
        log::info("saved the deformed surface to {}.obj, .ply and .stl ({} triangles)", (dir / "view_surface").string(), m.triangles.size());
        // The voxels left, in rest space on the scan's grid: for OpenVDB, and for 3D Slicer and ITK.
        const grid::LabelGrid kept = m_method->rest_voxels();
        kept.save(dir / "view_object.vdb");
        io::write_label_map(kept, dir / "view_object.seg.nrrd");
        io::write_label_map(kept, dir / "view_object.nii.gz");
        log::info("saved the object's {} voxels to {}.vdb, .seg.nrrd and .nii.gz", kept.active_voxel_count(), (dir / "view_object").string());
    } catch (const std::exception& e) {
        log::warn("not saved: {}", e.what()); // the session goes on
    }
}

void ViewSimulation::make_picture()
{
    const ViewRequests& q = m_channels.requests;
    RenderState& r = m_channels.pictures.write_slot();
    r.meshes.clear();
    const auto* dbg = dynamic_cast<const sim::DbgMethod*>(m_method.get()); // voxels and cages are the branched grid's
    if (q.show_voxels.load() && dbg) {
        r.meshes.push_back(voxel_boxes(dbg->simulation()));
        r.smooth = 0;
    } else {
        r.meshes.push_back(surface_picture(*m_method, 0, m_scene.object.label_colors)); // smoothed by the window's thread
        r.smooth = m_options.smooth;
    }
    for (std::size_t k = 0; k < m_scene.tools.size(); ++k) add_tool_drawings(m_tools.placed(k), m_scene.tools[k].push_margin_mm, r.meshes);
    add_obstacle_drawings(m_method->obstacles(), r.meshes.front(), r.meshes);
    if (q.show_cage.load() && dbg) {
        r.meshes.front().alpha = k_surface_alpha_over_cage;
        r.meshes.push_back(element_cage(dbg->simulation()));
    }
    r.t_s = m_loop.frames() * m_scene.solver.dt_s;
    r.model = std::to_string(m_method->element_count()) + " elements";
    if (const std::map<int, std::size_t> per = m_method->elements_per_level(); per.size() == 1) {
        r.model += ", level " + std::to_string(m_level);
    } else {
        for (const auto& [level, count] : per)
            r.model += (level == per.begin()->first ? ": " : ", ") + std::to_string(count) + " at level " + std::to_string(level);
    }
    r.notice = !m_fault_notice.empty() ? m_fault_notice
               : m_options.offered && m_method->cut_count() == 0
                   ? "An earlier session with this scene left " + std::to_string(m_options.offered->strokes.size()) +
                         " stroke(s) in its journal: press J to resume them"
               : m_now_s < m_level_notice_until_s ? m_level_notice
                                                  : std::string();
    const auto described = [&](std::size_t k) {
        const io::ToolSpec& tool = m_scene.tools[k];
        return tool.name + " (" +
               (tool.action == io::ToolAction::cut ? std::string(tool.cut_mode == io::CutMode::remove ? "cut, removing" : "cut, separating")
                : tool.action == io::ToolAction::wet ? std::string("wet")
                                                     : std::string("push")) +
               ")";
    };
    const auto active = static_cast<std::size_t>(q.active.load());
    r.tool = described(active);
    if (m_hands.size() > 1) { // each device's tool, and the one the keys act on
        r.tool.clear();
        for (std::size_t d = 0; d < m_hands.size(); ++d)
            r.tool += (d ? ",  " : "") + described(m_options.hands[d].tool) + " by " + m_options.hands[d].device;
        r.tool += "   keys: " + m_scene.tools[active].name;
    }
    m_channels.pictures.publish();
}

} // namespace vox::view
