#include "haptics/vendor_library.hpp"

#include "core/error.hpp"

#include <dlfcn.h>

#include <cstdlib>

namespace vox::haptics {

VendorLibrary::VendorLibrary(const std::string& soname, const char* env_var)
{
    const char* path = env_var ? std::getenv(env_var) : nullptr;
    m_name = path && *path ? std::string(path) : soname;
    // RTLD_NOW: a library that cannot resolve its own dependencies fails here, with the loader's
    // reason, not at the first call inside the 1 kHz loop.
    m_handle = ::dlopen(m_name.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!m_handle) {
        const char* error = ::dlerror();
        const std::string why = error ? error : "dlopen failed";
        const bool missing = why.find("No such file") != std::string::npos;
        const std::string where = path && *path ? std::string(" (from ") + env_var + ")"
                                                : std::string(" (searched by the dynamic loader: set LD_LIBRARY_PATH, or ") + env_var + " to its path)";
        throw InputError(m_name + (missing ? " not found" : " cannot be loaded") + where + ": " + why);
    }
}

VendorLibrary::~VendorLibrary()
{
    if (m_handle) ::dlclose(m_handle);
}

void* VendorLibrary::find(const char* symbol, bool required) const
{
    ::dlerror();
    void* f = ::dlsym(m_handle, symbol);
    if (!f && required) throw InputError(m_name + ": the library has no function " + symbol + " (not the vendor's library, or too old a version)");
    return f;
}

} // namespace vox::haptics
