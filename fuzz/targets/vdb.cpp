// Fuzz target: OpenVDB label grids (.vdb), through import: the child-process read of docs/input-safety.md.
// OpenVDB itself is not instrumented; this fuzzes the project's code around it (the child, its
// limits and messages, the label grid's selection and checks) and finds inputs the child misses.
#include "fuzz_input.hpp"

#include "io/object_import.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    return vox::fuzz::read_or_refuse(
        [&] { (void)vox::io::import_object(vox::fuzz::input_file(data, size, "in.vdb"), {}); });
}
