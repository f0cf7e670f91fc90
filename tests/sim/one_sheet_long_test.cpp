// The long run of the one-sheet property (`ctest -L long`, not in the default test command): a
// random sample of strokes of every kind the CI sample has, through objects of random stiffness,
// on both methods. VOX_STROKES strokes per method (default 40); VOX_SEED repeats a run (each run
// prints its seed) and VOX_STROKE=k runs only its stroke k.

#include "stroke_scenes.hpp"

#include <cstdlib>
#include <random>

namespace vox::sim {
namespace {

using namespace test;

class OneSheetLong : public ::testing::TestWithParam<io::SolverType> {};

TEST_P(OneSheetLong, RandomStrokesOfEveryKindEachOpenOneSheet)
{
    const char* count = std::getenv("VOX_STROKES");
    const char* seed_text = std::getenv("VOX_SEED");
    const char* only_text = std::getenv("VOX_STROKE");
    const int only = only_text ? std::atoi(only_text) : -1;
    const int strokes = only >= 0 ? only + 1 : count ? std::atoi(count) : 40;
    const unsigned seed = seed_text ? static_cast<unsigned>(std::strtoul(seed_text, nullptr, 10)) : std::random_device{}();
    std::printf("VOX_SEED=%u VOX_STROKES=%d\n", seed, strokes);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> along(25.0, 75.0), turn(-0.35, 0.35), tilt(-0.5, 0.5), unit(0.0, 1.0);
    std::uniform_int_distribution<int> kind(0, 5);
    for (int k = 0; k < strokes; ++k) {
        const double youngs_pa = 3e4 * std::pow(10.0, unit(rng)); // 30 to 300 kPa
        const StraightStroke s{along(rng), turn(rng), tilt(rng), unit(rng) < 0.5};
        const int what = kind(rng);
        io::Scene scene;
        std::string name;
        switch (what) {
        case 0: scene = rod_stroke(s, youngs_pa, k_both_ends, false, name = "rod_both_ends.json"); break;
        case 1: scene = rod_stroke(s, 10.0 * youngs_pa, k_one_end, false, name = "rod_swinging.json"); break;
        case 2: scene = rod_stroke(s, youngs_pa, k_both_ends, true, name = "rod_two_phase.json"); break;
        case 3: scene = curved_stroke(15.0 + 20.0 * unit(rng), 0.4 + 0.8 * unit(rng), 2.0 * M_PI * unit(rng), name = "curved_plate.json"); break;
        default: scene = drooping_slab(tilt(rng), 20.0 + 50.0 * unit(rng), 3.0 * youngs_pa, name = "drooping_slab.json"); break;
        }
        if (only >= 0 && k != only) continue;
        SCOPED_TRACE(testing::Message() << "stroke " << k << " (seed " << seed << "): " << name << ", E " << youngs_pa << " Pa, at " << s.x
                                        << ", turned " << s.yaw << ", tilted " << s.roll << (s.along_plane ? ", along its plane" : ", straight down"));
        const SheetCount n = run_and_count(scene, GetParam(), name);
        if (n.faces > 0) expect_one_sheet(n); // a stroke that misses a swinging rod opens nothing
        EXPECT_EQ(n.slivers, 0u);
    }
}

INSTANTIATE_TEST_SUITE_P(Methods, OneSheetLong, ::testing::Values(io::SolverType::dbg, io::SolverType::isxfem),
                         [](const auto& info) { return std::string(info.param == io::SolverType::dbg ? "dbg" : "isxfem"); });

} // namespace
} // namespace vox::sim
