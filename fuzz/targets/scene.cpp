// Fuzz target: scene files (JSON), as `voxsculpt check` parses them (the object itself is not built).
#include "fuzz_input.hpp"

#include "io/scene.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    return vox::fuzz::read_or_refuse(
        [&] { (void)vox::io::load_scene(vox::fuzz::input_file(data, size, "scene.json")); });
}
