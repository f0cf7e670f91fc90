#include "core/version.hpp"

namespace vox {

// VOX_VERSION is defined for this file only (src/core/CMakeLists.txt): a new version recompiles
// one file.
const char* program_version() { return "voxsculpt " VOX_VERSION; }

} // namespace vox
