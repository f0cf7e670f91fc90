// Fuzz target: continuous-collision query files (data/ccd-queries), read and scored as `voxsculpt ccd-check` does.
#include "fuzz_input.hpp"

#include "contact/ccd_queries.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    return vox::fuzz::read_or_refuse([&] {
        const auto queries = vox::contact::read_ccd_queries(vox::fuzz::input_file(data, size, "queries.csv"));
        (void)vox::contact::score_ccd(queries, true);
        (void)vox::contact::score_ccd(queries, false);
    });
}
