// Fuzz target: haptic session recordings (CSV), as `--replay` reads them.
#include "fuzz_input.hpp"

#include "haptics/recording.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    return vox::fuzz::read_or_refuse(
        [&] { (void)vox::haptics::read_recording(vox::fuzz::input_file(data, size, "session.csv")); });
}
