#include "io/volume_reader.hpp"

#include "core/error.hpp"
#include "io/text_parsing.hpp"

#include <algorithm>
#include <cctype>

namespace vox::io {
namespace {
bool ends_with(const std::string& s, const std::string& suffix)
{
    return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}
} // namespace

bool is_volume_path(const std::string& path)
{
    const std::string p = detail::lower_case(path);
    for (const char* ext : {".inr", ".inr.gz", ".nii", ".nii.gz", ".mhd", ".mha", ".nrrd", ".nhdr"})
        if (ends_with(p, ext)) return true;
    return false;
}

Volume read_volume(const std::string& path)
{
    const std::string p = detail::lower_case(path);
    if (ends_with(p, ".inr") || ends_with(p, ".inr.gz")) return read_inr(path);
    if (ends_with(p, ".nii") || ends_with(p, ".nii.gz")) return read_nifti(path);
    if (ends_with(p, ".mhd") || ends_with(p, ".mha")) return read_metaimage(path);
    if (ends_with(p, ".nrrd") || ends_with(p, ".nhdr")) return read_nrrd(path);
    throw file_error(path, "unknown volume format (expected .inr[.gz], .nii[.gz], .mhd, .mha, .nrrd or .nhdr)");
}

} // namespace vox::io
