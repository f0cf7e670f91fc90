#pragma once
// `voxsculpt run` for scenes with "solver": {"type": "isxfem"}: the scene's blades and scalpels
// cut the tetrahedra along their mid-plane where their strokes pass through the object; the
// object falls, sags and comes apart under gravity and its supports. Writes DIR/stats.json,
// DIR/final.obj and DIR/frame_NNNNN.obj like the branched-grid runs, and with `pictures`
// DIR/frame_NNNNN.png every `render_every` frames and DIR/final.png (app/scene_pictures.hpp).

#include "app/scene_pictures.hpp"
#include "io/scene.hpp"

#include <filesystem>
#include <optional>
#include <string>

namespace vox::app {

void run_isxfem(const io::Scene& scene, const std::string& scene_path, std::optional<int> frames, const std::filesystem::path& out,
                ScenePictures* pictures = nullptr, int render_every = 0);

} // namespace vox::app
