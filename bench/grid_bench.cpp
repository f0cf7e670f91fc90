// Branched-grid benchmark on the bundled liver (label 255, 3,160,496 voxels):
//  - build: fine voxels, levels 1..5 with every element's stiffness and mass evaluated;
//  - update: removing a b x b x b block of fine voxels (b = 5, 10, 20) and updating the grid and
//    the matrices of every element the update created or changed, on the liver and on a smaller
//    block phantom, to show the cost follows the cut, not the object.
// Usage: vox_grid_bench [RUNS] (default 5). Prints a Markdown table for the README.

#include "bench/bench_stats.hpp"
#include "core/memory_usage.hpp"
#include "grid/branched_grid.hpp"
#include "grid/phantom.hpp"
#include "io/selection.hpp"
#include "io/volume_reader.hpp"

#include <cstdio>
#include <cstdlib>

using namespace vox;
using namespace vox::grid;

namespace {

const std::vector<ElasticMaterial> k_materials{{lame_from_young_poisson(3e4, 0.45), 1060.0}};

/// Evaluates every element matrix of the level (full cells share theirs); returns a checksum so
/// the work cannot be optimised away, and counts partial elements.
double evaluate_matrices(const BranchedGrid& grid, int l, const std::vector<std::uint32_t>& elements,
                         std::size_t& partial)
{
    double checksum = 0.0;
    for (std::uint32_t e : elements) {
        if (!grid.level(l).elements[e].alive) continue;
        if (grid.is_full(l, e)) continue;
        ++partial;
        checksum += grid.stiffness(l, e)(0, 0) + grid.mass(l, e)(0, 0);
    }
    return checksum;
}

std::vector<std::uint32_t> all_elements(const BranchedGrid& grid, int l)
{
    std::vector<std::uint32_t> out(grid.level(l).elements.size());
    for (std::uint32_t e = 0; e < out.size(); ++e) out[e] = e;
    return out;
}

/// Removes the b^3 block whose lowest corner is `corner` and re-evaluates the matrices of the
/// elements the update created or changed, at every level; returns wall milliseconds.
double timed_cut(BranchedGrid& grid, const Coord& corner, int b)
{
    std::vector<Coord> block;
    for (int z = 0; z < b; ++z)
        for (int y = 0; y < b; ++y)
            for (int x = 0; x < b; ++x) block.push_back(corner + Coord(x, y, z));
    double checksum = 0.0;
    const double ms = bench::time_ms([&] {
        const UpdateReport report = grid.update(block, {});
        for (int l = 1; l <= grid.max_level(); ++l) {
            std::vector<std::uint32_t> changed = report.levels[l].updated;
            for (const auto& [id, from] : report.levels[l].created) changed.push_back(id);
            std::size_t partial = 0;
            checksum += evaluate_matrices(grid, l, changed, partial);
        }
    });
    if (checksum == 12345.678) std::puts(""); // keep the evaluation
    return ms;
}

/// Corners of non-overlapping b^3 blocks fully inside the object (all voxels present), spread
/// over it; at most `count`.
std::vector<Coord> block_corners(const BranchedGrid& grid, int b, std::size_t count)
{
    std::vector<Coord> out;
    const FineVoxels& v = grid.voxels();
    const std::uint32_t stride = std::max<std::uint32_t>(1, v.slots() / static_cast<std::uint32_t>(count * 40));
    for (std::uint32_t s = 0; s < v.slots() && out.size() < count; s += stride) {
        const Coord c = v.coord(s);
        bool inside = true, apart = true;
        for (const Coord& o : out) apart = apart && ((c - o).cwiseAbs().maxCoeff() >= 2 * b);
        for (int z = -1; z <= b && inside && apart; ++z)
            for (int y = -1; y <= b && inside; ++y)
                for (int x = -1; x <= b && inside; ++x) inside = v.find(c + Coord(x, y, z)) != FineVoxels::missing;
        if (inside && apart) out.push_back(c);
    }
    return out;
}

void cut_rows(const char* object, const LabelGrid& labels, int runs)
{
    for (int b : {5, 10, 20}) {
        BranchedGrid grid(FineVoxels(labels, [](std::int32_t) { return 0; }), k_materials, 5);
        const auto corners = block_corners(grid, b, static_cast<std::size_t>(runs));
        std::vector<double> ms;
        for (const Coord& c : corners) ms.push_back(timed_cut(grid, c, b));
        const auto s = bench::summarize(ms);
        std::printf("| remove %d^3 voxels from the %s, update levels 1-5 and matrices | %.2f ms | %.2f - %.2f ms | %zu |\n",
                    b, object, s.median, s.min, s.max, s.runs);
    }
}

} // namespace

int main(int argc, char** argv)
{
    const int runs = argc > 1 ? std::max(1, std::atoi(argv[1])) : 5;
    io::Selection selection;
    selection.labels = {255};
    const LabelGrid liver = io::select_voxels(io::read_volume(VOX_SOURCE_DIR "/data/liver.inr.gz"), selection);

    std::printf("machine: %s\n\n", bench::machine().c_str());
    std::printf("| what | median | min - max | runs |\n|---|---|---|---|\n");

    std::vector<double> build_ms;
    std::size_t partial = 0;
    std::uint64_t peak = 0;
    for (int r = 0; r < runs; ++r) {
        partial = 0;
        build_ms.push_back(bench::time_ms([&] {
            const BranchedGrid grid(FineVoxels(liver, [](std::int32_t) { return 0; }), k_materials, 5);
            double checksum = 0.0;
            for (int l = 1; l <= 5; ++l) checksum += evaluate_matrices(grid, l, all_elements(grid, l), partial);
            if (checksum == 12345.678) std::puts("");
        }));
        peak = peak_memory_bytes();
    }
    const auto b = bench::summarize(build_ms);
    std::printf("| liver: fine voxels + levels 1-5 + all element matrices (%zu partial evaluated, full cells shared) "
                "| %.0f ms | %.0f - %.0f ms | %zu |\n",
                partial, b.median, b.min, b.max, b.runs);
    std::printf("| liver: peak memory of the build | %.0f MB | | |\n", static_cast<double>(peak) / (1 << 20));

    cut_rows("liver (3.16 M voxels)", liver, runs);
    PhantomSpec block = default_phantom(PhantomShape::block);
    block.size_mm = {64, 64, 64};
    cut_rows("64^3 block (262 k voxels)", make_phantom(block), runs);
    return 0;
}
