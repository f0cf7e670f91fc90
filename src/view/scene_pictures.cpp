#include "view/scene_pictures.hpp"

#include "core/error.hpp"
#include "core/label_palette.hpp"
#include "sim/dbg_method.hpp"
#include "sim/obstacles.hpp"

#include <sstream>

namespace vox::view {
namespace {

/// Cut surfaces are drawn lighter, as freshly cut tissue or clay looks.
const Eigen::Vector3f k_cut_tone(0.95f, 0.70f, 0.62f);

} // namespace

Eigen::Vector3d scene_up(const io::Scene& scene)
{
    const double g = scene.gravity_m_s2.norm();
    return g > 0.0 ? Eigen::Vector3d(-scene.gravity_m_s2 / g) : Eigen::Vector3d::UnitZ();
}

std::pair<int, int> parse_size(const std::string& size)
{
    std::istringstream in(size);
    int w = 0, h = 0;
    char x = 0;
    if (in >> w >> x >> h && (x == 'x' || x == 'X') && in.peek() == std::char_traits<char>::eof() && w >= 1 && h >= 1 && w <= 8192 &&
        h <= 8192)
        return {w, h};
    throw InputError("--size \"" + size + "\": expected WIDTHxHEIGHT in pixels, each 1 to 8192 (for example 960x720)");
}

render::DrawMesh surface_drawing(const surface::SurfaceMesh& mesh, int smooth, const LabelColors& colors)
{
    render::DrawMesh d;
    d.positions.reserve(mesh.positions.size());
    for (const Eigen::Vector3d& p : mesh.positions) d.positions.push_back(p.cast<float>());
    d.colors.reserve(mesh.positions.size());
    for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
        const std::int32_t label = v < mesh.labels.size() ? mesh.labels[v] : 0;
        const auto own = colors.find(label);
        d.colors.push_back(own != colors.end() ? Eigen::Vector3f(own->second.cast<float>()) : Eigen::Vector3f(label_color(label).cast<float>()));
    }
    d.indices.reserve(3 * mesh.triangles.size());
    for (const Eigen::Vector3i& t : mesh.triangles)
        for (int c = 0; c < 3; ++c) d.indices.push_back(static_cast<std::uint32_t>(t[c]));
    render::smooth_for_display(d, smooth);
    render::compute_normals(d);
    return d;
}

void add_tool_drawings(const contact::PlacedShape& tool, double margin_mm, std::vector<render::DrawMesh>& out)
{
    if (!tool.shape) return;
    auto drawing = [&](double margin, const Eigen::Vector3f& color, float alpha) {
        const contact::TriangleMesh m = tool.shape->mesh(margin);
        render::DrawMesh d;
        for (const Eigen::Vector3d& p : m.positions) d.positions.push_back((tool.position + tool.orientation * p).cast<float>());
        d.colors.assign(d.positions.size(), color);
        for (const Eigen::Vector3i& t : m.triangles)
            for (int c = 0; c < 3; ++c) d.indices.push_back(static_cast<std::uint32_t>(t[c]));
        render::compute_normals(d);
        d.alpha = alpha;
        out.push_back(std::move(d));
    };
    drawing(0.0, {0.55f, 0.58f, 0.62f}, 1.0f); // steel
    if (margin_mm > 0.05) drawing(margin_mm, {0.35f, 0.55f, 0.85f}, 0.25f);
}

void add_obstacle_drawings(const std::vector<contact::Obstacle>& obstacles, const render::DrawMesh& object, std::vector<render::DrawMesh>& out)
{
    if (obstacles.empty()) return;
    Eigen::AlignedBox3d around;
    around.setEmpty();
    for (const std::uint32_t i : object.indices) around.extend(object.positions[i].cast<double>());
    const contact::TriangleMesh m = sim::obstacles_mesh(obstacles, around);
    render::DrawMesh d;
    for (const Eigen::Vector3d& p : m.positions) d.positions.push_back(p.cast<float>());
    d.colors.assign(d.positions.size(), Eigen::Vector3f(0.62f, 0.66f, 0.70f)); // brushed steel, as an instrument table
    for (const Eigen::Vector3i& t : m.triangles)
        for (int c = 0; c < 3; ++c) d.indices.push_back(static_cast<std::uint32_t>(t[c]));
    render::compute_normals(d);
    d.alpha = 0.45f; // the object shows through from any side
    d.frames_camera = false;
    out.push_back(std::move(d));
}

ScenePictures::ScenePictures(const PictureOptions& options) : m_options(options) {}

void ScenePictures::write(const std::filesystem::path& path, const std::vector<render::DrawMesh>& meshes)
{
    if (!m_camera) {
        std::vector<Eigen::Vector3f> used; // the vertices in use (a surface keeps free slots)
        for (const render::DrawMesh& m : meshes)
            if (m.frames_camera)
                for (const std::uint32_t i : m.indices) used.push_back(m.positions[i]);
        m_camera = render::fit_camera(m_options.camera, used, static_cast<double>(m_options.width) / m_options.height);
    }
    render::write_png(path, m_renderer.render(meshes, *m_camera, m_options.width, m_options.height));
}

void ScenePictures::write(const std::filesystem::path& path, const sim::Method& method, const sim::ToolPolicy& tools, const io::Scene& scene)
{
    std::vector<render::DrawMesh> meshes{surface_picture(method, m_options.smooth, scene.object.label_colors)};
    for (std::size_t k = 0; k < scene.tools.size(); ++k) add_tool_drawings(tools.placed(k), scene.tools[k].push_margin_mm, meshes);
    add_obstacle_drawings(method.obstacles(), meshes.front(), meshes);
    if (const auto* dbg = dynamic_cast<const sim::DbgMethod*>(&method); dbg && m_options.cage) {
        meshes.front().alpha = k_surface_alpha_over_cage;
        meshes.push_back(element_cage(dbg->simulation()));
    }
    write(path, meshes);
}

render::DrawMesh surface_picture(const sim::Method& method, int smooth, const LabelColors& colors)
{
    render::DrawMesh d = surface_drawing(method.surface_mesh(), smooth, colors);
    // Cut surfaces lighter, as freshly cut tissue or clay looks; wet material darker and cooler,
    // by its water content (what a sculptor sees on soaked clay).
    const std::vector<sim::SurfaceMark> marks = method.surface_marks();
    const std::vector<float> wetness = method.surface_wetness();
    for (std::size_t v = 0; v < d.colors.size(); ++v) {
        const sim::SurfaceMark m = v < marks.size() ? marks[v] : sim::SurfaceMark::surface;
        if (m == sim::SurfaceMark::cut) d.colors[v] = 0.5f * d.colors[v] + 0.5f * k_cut_tone;
        if (m == sim::SurfaceMark::coupled) d.colors[v] = Eigen::Vector3f(1.0f, 0.45f, 0.05f);
        const float w = v < wetness.size() ? wetness[v] : 0.0f;
        if (w > 0.0f) d.colors[v] = (1.0f - 0.5f * w) * d.colors[v] + 0.5f * w * Eigen::Vector3f(0.30f, 0.32f, 0.38f);
    }
    return d;
}

render::DrawMesh voxel_boxes(const sim::DbgSimulation& sim)
{
    render::DrawMesh d;
    const cut::ModelSurface& surface = sim.surface();
    const grid::FineVoxels& voxels = surface.grid().voxels();
    const auto& x = sim.solver().positions();
    // Half a voxel in an element's local units (two levels: each element's own).
    const auto half_voxel = [&](std::uint32_t e) { const int l = sim.model().elements()[e].level; return l == 0 ? 0.5 : 0.5 / static_cast<double>(1 << l); };
    for (std::uint32_t v = 0; v < voxels.slots(); ++v) {
        if (!voxels.alive(v)) continue;
        const grid::Coord c = voxels.coord(v);
        Eigen::Vector3d local;
        const std::uint32_t e = surface.voxel_element(v, local);
        const double half = half_voxel(e);
        // A checkerboard of two shades, so that each voxel shows.
        const Eigen::Vector3f color = ((c.x() + c.y() + c.z()) % 2 == 0 ? 0.92f : 0.78f) * label_color(voxels.label(v)).cast<float>();
        for (int axis = 0; axis < 3; ++axis)
            for (const int side : {-1, 1}) {
                const std::uint32_t n = voxels.find(c + side * grid::Coord::Unit(axis));
                const bool joined = n != grid::FineVoxels::missing && voxels.alive(n) && !voxels.face_disconnected(side < 0 ? n : v, axis);
                if (joined) continue;
                // The face's corners: offsets of +-1/2 voxel across the two other axes.
                const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
                const auto first = static_cast<std::uint32_t>(d.positions.size());
                for (const auto& [s1, s2] : {std::pair{-1, -1}, std::pair{1, -1}, std::pair{1, 1}, std::pair{-1, 1}}) {
                    Eigen::Vector3d offset = Eigen::Vector3d::Zero();
                    offset[axis] = 0.5 * side;
                    offset[a1] = 0.5 * s1;
                    offset[a2] = 0.5 * s2;
                    const Eigen::Vector3d rest = voxels.world_mm(c.cast<double>() + offset);
                    d.positions.push_back(surface.deformed_mm(e, local + 2.0 * half * offset, rest, x).cast<float>());
                    d.colors.push_back(color);
                }
                // Counter-clockwise seen from outside: the corner order above turns about +axis.
                if (side > 0) d.indices.insert(d.indices.end(), {first, first + 1, first + 2, first, first + 2, first + 3});
                else d.indices.insert(d.indices.end(), {first, first + 2, first + 1, first, first + 3, first + 2});
            }
    }
    render::compute_normals(d);
    return d;
}

render::DrawMesh element_cage(const sim::DbgSimulation& sim)
{
    render::DrawMesh d;
    d.lines = true;
    const auto& x = sim.solver().positions();
    for (const Eigen::Vector3d& p : x) d.positions.push_back((1e3 * p).cast<float>());
    d.colors.assign(d.positions.size(), k_cage_coarse);
    // Two levels: the fine region's nodes in another colour, and the border nodes tied to the
    // coarse side in a third, so the interface shows.
    const fem::HexModel& model = sim.model();
    if (model.mixed()) {
        for (std::uint32_t n = 0; n < model.node_count(); ++n)
            if (model.node_levels()[n] == model.level()) d.colors[n] = k_cage_fine;
        for (const grid::MixedLevels::Tie& t : model.ties()) d.colors[t.node] = k_cage_tied;
    }
    // The 12 edges of a hexahedron by corner numbers (bit 0: +x, bit 1: +y, bit 2: +z).
    static constexpr int edges[12][2] = {{0, 1}, {2, 3}, {4, 5}, {6, 7}, {0, 2}, {1, 3}, {4, 6}, {5, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
    for (const fem::HexElement& e : sim.model().elements())
        for (const auto& [a, b] : edges) d.indices.insert(d.indices.end(), {e.dof_node[static_cast<std::size_t>(a)], e.dof_node[static_cast<std::size_t>(b)]});
    return d;
}

} // namespace vox::view
