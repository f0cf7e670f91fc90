// Fuzz target: INRIMAGE-4 (.inr, .inr.gz), through import.
#include "fuzz_input.hpp"

#include "io/object_import.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    return vox::fuzz::read_or_refuse([&] {
        const std::string name = vox::fuzz::is_gzip(data, size) ? "in.inr.gz" : "in.inr";
        (void)vox::io::import_object(vox::fuzz::input_file(data, size, name), {});
    });
}
