#include "core/error.hpp"

namespace vox {

InputError file_error(const std::string& path, const std::string& what)
{
    return InputError(path + ": " + what);
}

} // namespace vox
