// Fuzz target: NIfTI-1 and NIfTI-2 (.nii, .nii.gz) through import, as `voxsculpt import` reads them.
#include "fuzz_input.hpp"

#include "io/object_import.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    return vox::fuzz::read_or_refuse([&] {
        const std::string name = vox::fuzz::is_gzip(data, size) ? "in.nii.gz" : "in.nii";
        (void)vox::io::import_object(vox::fuzz::input_file(data, size, name), {});
    });
}
