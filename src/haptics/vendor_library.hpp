#pragma once
// A vendor's device library opened at run time (dlopen), so the program builds, ships and runs
// without the vendor's SDK: the dynamic loader finds it by its soname (LD_LIBRARY_PATH works), or
// it is taken from the path an environment variable names. Functions are resolved by name: a
// required one that is missing is an error naming it; an optional one is null when absent.

#include <string>

namespace vox::haptics {

class VendorLibrary {
public:
    /// Opens `soname` ("libHD.so"), or the file `env_var` ("VOX_LIBHD") names when it is set. Throws
    /// InputError naming the library and the loader's reason when it cannot be opened.
    VendorLibrary(const std::string& soname, const char* env_var);
    ~VendorLibrary();
    VendorLibrary(const VendorLibrary&) = delete;
    VendorLibrary& operator=(const VendorLibrary&) = delete;

    /// The function `symbol`, cast to F. Throws InputError naming the library and the symbol when
    /// the library lacks it.
    template <class F> F required(const char* symbol) const { return reinterpret_cast<F>(find(symbol, true)); }
    /// The function `symbol`, or null when the library lacks it.
    template <class F> F optional(const char* symbol) const { return reinterpret_cast<F>(find(symbol, false)); }
    /// What was opened: the path given, or the soname the loader searched for.
    [[nodiscard]] const std::string& name() const { return m_name; }

private:
    void* find(const char* symbol, bool required) const;
    void* m_handle = nullptr;
    std::string m_name;
};

} // namespace vox::haptics
