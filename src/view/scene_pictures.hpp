#pragma once
// Pictures of a simulation: the deformed surface shaded per material label, and each placed
// tool (its cutting shape in steel, its pushing shape as a translucent shell), rendered offscreen
// to PNG files. A sequence keeps one camera, framed on the first picture, so frames line up.

#include "render/camera.hpp"
#include "sim/dbg_simulation.hpp"
#include "sim/method.hpp"
#include "sim/tool_policy.hpp"
#include "render/offscreen_context.hpp"
#include "render/renderer.hpp"
#include "surface/embedded_surface.hpp"

#include <filesystem>
#include <map>
#include <memory>
#include <optional>

namespace vox::view {

struct PictureOptions {
    render::CameraSpec camera;
    int width = 960, height = 720;
    int smooth = 30; ///< display smoothing of the surface (Taubin iterations; 0: the voxel steps as they are)
    bool cage = false; ///< the branched grid's element cage drawn through a translucent surface (element_cage)
};

/// How translucent the surface is drawn over the element cage.
inline constexpr float k_surface_alpha_over_cage = 0.35f;

/// The picture's up for a scene: against gravity (a patient on the table is seen from above, the
/// anterior side up), or +z without gravity.
[[nodiscard]] Eigen::Vector3d scene_up(const io::Scene& scene);

/// Parses "WxH" (each 1 to 8192); throws InputError naming the value.
[[nodiscard]] std::pair<int, int> parse_size(const std::string& size);

/// Colours by label that replace the palette's (a segmentation's own colours), RGB 0..1.
using LabelColors = std::map<std::int32_t, Eigen::Vector3d>;

/// The surface mesh (world mm, labels per vertex) as a drawable mesh, smoothed for display by
/// `smooth` Taubin iterations; coloured by `colors`, else by the label palette.
[[nodiscard]] render::DrawMesh surface_drawing(const surface::SurfaceMesh& mesh, int smooth, const LabelColors& colors = {});
/// A method's deformed surface as drawn: label colours, wet material darker, the surface cuts
/// made in a lighter, pinker tone, and where the cuts could not separate all pieces of an
/// element (sim::SurfaceMark::coupled) in orange.
[[nodiscard]] render::DrawMesh surface_picture(const sim::Method& method, int smooth, const LabelColors& colors = {});
/// The fine voxels as boxes where the model has moved them: every face of a voxel not joined to a
/// neighbour (the object's outside, removed neighbours, faces a cut opened), each corner carried
/// by its element's trilinear map; coloured by label.
[[nodiscard]] render::DrawMesh voxel_boxes(const sim::DbgSimulation& sim);
/// The simulated level's elements as a wire cage (their corner nodes where they are now), dark
/// blue; on two levels, the fine region's in orange and its border nodes tied to the coarse side
/// in green.
[[nodiscard]] render::DrawMesh element_cage(const sim::DbgSimulation& sim);
inline const Eigen::Vector3f k_cage_coarse{0.15f, 0.2f, 0.3f}, k_cage_fine{0.95f, 0.45f, 0.1f}, k_cage_tied{0.2f, 0.75f, 0.3f};
/// A tool's shapes where it is placed: the inner one opaque, the pushing one (grown by
/// `margin_mm`) translucent when the margin is visible.
void add_tool_drawings(const contact::PlacedShape& tool, double margin_mm, std::vector<render::DrawMesh>& out);

/// The scene's obstacles, translucent, planes as squares reaching well beyond `object` (the
/// object's drawing); the camera is not framed on them.
void add_obstacle_drawings(const std::vector<contact::Obstacle>& obstacles, const render::DrawMesh& object, std::vector<render::DrawMesh>& out);

class ScenePictures {
public:
    /// Makes the offscreen context (throws render::NoOpenGL when there is none).
    explicit ScenePictures(const PictureOptions& options);

    /// Writes the picture of `meshes` to `path` (PNG), framing the camera on them the first time.
    void write(const std::filesystem::path& path, const std::vector<render::DrawMesh>& meshes);
    /// The method's surface and the placed tools (and the cage, with PictureOptions::cage).
    void write(const std::filesystem::path& path, const sim::Method& method, const sim::ToolPolicy& tools, const io::Scene& scene);

    [[nodiscard]] const std::string& context_description() const { return m_context.description(); }

private:
    PictureOptions m_options;
    render::OffscreenContext m_context;
    render::Renderer m_renderer;
    std::optional<render::Camera> m_camera;
};

} // namespace vox::view
