// Embedded-surface benchmark on the bundled liver (label 255), surface embedded at level 3:
//  - full extraction (about 443 k triangles);
//  - local update after removing a 10 x 10 x 10 block of voxels (surface alone, and grid + surface);
//  - deforming every vertex from node positions.
// Usage: vox_surface_bench [RUNS] (default 7). Prints a Markdown table for the README.

#include "bench/bench_stats.hpp"
#include "grid/branched_grid.hpp"
#include "io/selection.hpp"
#include "io/volume_reader.hpp"
#include "surface/embedded_surface.hpp"

#include <cstdio>
#include <cstdlib>
#include <random>

using namespace vox;
using namespace vox::grid;

int main(int argc, char** argv)
{
    const int runs = argc > 1 ? std::max(1, std::atoi(argv[1])) : 7;
    constexpr int level = 3;
    io::Selection selection;
    selection.labels = {255};
    const LabelGrid liver = io::select_voxels(io::read_volume(VOX_SOURCE_DIR "/data/liver.inr.gz"), selection);
    const std::vector<ElasticMaterial> materials{{lame_from_young_poisson(3e4, 0.45), 1060.0}};
    BranchedGrid grid(FineVoxels(liver, [](std::int32_t) { return 0; }), materials, level);

    std::printf("machine: %s\n\n| what | median | min - max | runs |\n|---|---|---|---|\n", bench::machine().c_str());

    std::vector<double> extract_ms;
    std::size_t triangles = 0;
    for (int r = 0; r < runs; ++r)
        extract_ms.push_back(bench::time_ms([&] { triangles = surface::EmbeddedSurface(grid, level).triangle_count(); }));
    auto s = bench::summarize(extract_ms);
    std::printf("| full extraction of the liver surface (%zu triangles) | %.0f ms | %.0f - %.0f ms | %zu |\n", triangles,
                s.median, s.min, s.max, s.runs);

    surface::EmbeddedSurface surf(grid, level);
    // Deformation: every vertex from perturbed node positions.
    std::vector<Eigen::Vector3d> nodes = grid.rest_node_positions(level);
    std::mt19937 rng(1);
    std::normal_distribution<double> noise(0.0, 0.5);
    for (auto& p : nodes)
        if (p.allFinite()) p += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    std::vector<Eigen::Vector3d> out;
    surf.deform(grid, nodes, out); // first call sizes the output
    std::vector<double> deform_ms;
    for (int r = 0; r < runs; ++r) deform_ms.push_back(bench::time_ms([&] { surf.deform(grid, nodes, out); }));
    s = bench::summarize(deform_ms);
    std::printf("| deform all %zu vertices from %zu node positions | %.2f ms | %.2f - %.2f ms | %zu |\n",
                surf.vertex_count(), nodes.size(), s.median, s.min, s.max, s.runs);

    // Local updates: 10^3 blocks at different places inside the liver.
    std::vector<double> surface_ms, total_ms;
    const FineVoxels& v = grid.voxels();
    std::vector<Coord> corners;
    for (std::uint32_t slot = 0; slot < v.slots() && corners.size() < static_cast<std::size_t>(runs); slot += 9973) {
        const Coord c = v.coord(slot);
        bool inside = true;
        for (const Coord& o : corners) inside = inside && (c - o).cwiseAbs().maxCoeff() >= 24;
        for (int z = -1; z <= 10 && inside; ++z)
            for (int y = -1; y <= 10 && inside; ++y)
                for (int x = -1; x <= 10 && inside; ++x) inside = v.find(c + Coord(x, y, z)) != FineVoxels::missing;
        if (inside) corners.push_back(c);
    }
    for (const Coord& c : corners) {
        std::vector<Coord> block;
        for (int z = 0; z < 10; ++z)
            for (int y = 0; y < 10; ++y)
                for (int x = 0; x < 10; ++x) block.push_back(c + Coord(x, y, z));
        UpdateReport report;
        const double grid_ms = bench::time_ms([&] { report = grid.update(block, {}); });
        const double ms = bench::time_ms([&] { surf.update(grid, block, {}, report); });
        surface_ms.push_back(ms);
        total_ms.push_back(ms + grid_ms);
    }
    s = bench::summarize(surface_ms);
    std::printf("| surface update after removing a 10^3 block | %.2f ms | %.2f - %.2f ms | %zu |\n", s.median, s.min,
                s.max, s.runs);
    s = bench::summarize(total_ms);
    std::printf("| grid (levels 1-3) + surface update for the same cut | %.2f ms | %.2f - %.2f ms | %zu |\n", s.median,
                s.min, s.max, s.runs);
    return 0;
}
