#pragma once
// The bundled scenes the simulation core's tests run, with the method they are run by.

#include "io/scene.hpp"
#include "io/scene_object.hpp"
#include "sim/method_factory.hpp"

#include <memory>
#include <string>

namespace vox::sim::test {

/// data/scenes/NAME, simulated by `type` (cut modes the file leaves open take its default).
inline io::Scene bundled(const std::string& name, io::SolverType type)
{
    io::Scene scene = io::load_scene(VOX_SOURCE_DIR "/data/scenes/" + name);
    io::use_method(scene, type);
    return scene;
}

/// The scene's method on its object, as `voxsculpt run` opens it.
inline std::unique_ptr<Method> open(const io::Scene& scene)
{
    return open_method(scene, std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene))).method;
}

} // namespace vox::sim::test
