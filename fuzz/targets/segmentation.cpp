// Fuzz target: a 3D Slicer segmentation (.seg.nrrd: layers and Segment<N>_ keys), every segment
// picked, through import.
#include "fuzz_input.hpp"

#include "io/object_import.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    return vox::fuzz::read_or_refuse(
        [&] { (void)vox::io::import_object(vox::fuzz::input_file(data, size, "in.seg.nrrd"), {}); });
}
