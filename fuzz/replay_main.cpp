// Replays inputs through one fuzz target without libFuzzer, so the normal build (and CI) runs
// every corpus in seconds. Arguments are files or folders of files; a folder's files run in name
// order. A reader that throws anything but an InputError, or crashes, ends the run with a failure.

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

#include "fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

int main(int argc, char** argv)
{
    std::vector<std::filesystem::path> inputs;
    for (int a = 1; a < argc; ++a) {
        const std::filesystem::path arg = argv[a];
        if (std::filesystem::is_directory(arg)) {
            for (const auto& entry : std::filesystem::directory_iterator(arg))
                if (entry.is_regular_file()) inputs.push_back(entry.path());
        } else if (std::filesystem::is_regular_file(arg)) {
            inputs.push_back(arg);
        } else {
            std::fprintf(stderr, "replay: %s: no such file or folder\n", arg.c_str());
            return 2;
        }
    }
    std::sort(inputs.begin(), inputs.end());
    std::size_t seeds_refused = 0;
    for (const std::filesystem::path& path : inputs) {
        const std::size_t refused_before = vox::fuzz::refused_count();
        std::ifstream in(path, std::ios::binary);
        const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        // An empty input gets a valid pointer, as libFuzzer gives.
        static const std::uint8_t none = 0;
        const auto* data = bytes.empty() ? &none : reinterpret_cast<const std::uint8_t*>(bytes.data());
        LLVMFuzzerTestOneInput(data, bytes.size());
        // A seed is a valid file: its refusal means the seed or the reader is wrong.
        if (path.filename().string().starts_with("seed_") && vox::fuzz::refused_count() > refused_before) {
            std::fprintf(stderr, "replay: seed %s was refused: %s\n", path.c_str(), vox::fuzz::last_refusal().c_str());
            ++seeds_refused;
        }
    }
    std::printf("replay: %zu inputs, %zu refused, no crash\n", inputs.size(), vox::fuzz::refused_count());
    return inputs.empty() || seeds_refused > 0 ? 1 : 0;
}
