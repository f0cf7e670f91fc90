// Fuzz target: one DICOM file (a single-slice series) through import, GDCM's parser and decoders
// included.
#include "fuzz_input.hpp"

#include "io/object_import.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    return vox::fuzz::read_or_refuse(
        [&] { (void)vox::io::import_object(vox::fuzz::input_file(data, size, "in.dcm"), {}); });
}
