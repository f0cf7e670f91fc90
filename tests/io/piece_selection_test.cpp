#include "io/piece_selection.hpp"

#include "core/error.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <deque>
#include <random>

using namespace vox::io;
using vox::grid::Coord;
using vox::grid::LabelGrid;
using vox::grid::VoxelPieces;

namespace {

/// Three cubes apart from each other: 3^3 at the origin, 2^3 at x = 10, one voxel at x = 20.
/// Voxels 2 mm, so voxel (i, j, k) is centred at (2i, 2j, 2k) mm.
LabelGrid three_cubes()
{
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    m.topLeftCorner<3, 3>() *= 2.0;
    LabelGrid g(m);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            for (int k = 0; k < 3; ++k) g.set({i, j, k}, 1);
    for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j)
            for (int k = 0; k < 2; ++k) g.set({10 + i, j, k}, 2);
    g.set({20, 0, 0}, 3);
    return g;
}

std::uint64_t kept_voxels(const PieceSelection& s)
{
    return select_pieces(three_cubes(), s, "cubes").active_voxel_count();
}

} // namespace

TEST(VoxelPieces, MatchAFloodFillOnRandomVoxels)
{
    // An independent count: breadth-first flood fill over a dense array, face neighbours only.
    constexpr int n = 18;
    std::mt19937 random(7);
    std::bernoulli_distribution occupied(0.3);
    std::vector<char> dense(n * n * n);
    LabelGrid g;
    for (int k = 0; k < n; ++k)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i)
                if ((dense[static_cast<std::size_t>(i + n * (j + n * k))] = occupied(random) ? 1 : 0)) g.set({i - 5, j, k + 3}, 1);
    std::vector<int> component(dense.size(), -1);
    std::vector<std::uint64_t> sizes;
    for (std::size_t start = 0; start < dense.size(); ++start) {
        if (!dense[start] || component[start] >= 0) continue;
        std::deque<std::size_t> queue{start};
        component[start] = static_cast<int>(sizes.size());
        std::uint64_t size = 0;
        while (!queue.empty()) {
            const std::size_t v = queue.front();
            queue.pop_front();
            ++size;
            const int i = static_cast<int>(v % n), j = static_cast<int>((v / n) % n), k = static_cast<int>(v / (n * n));
            const std::array<std::array<int, 3>, 6> steps{{{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}}};
            for (const auto& d : steps) {
                const int a = i + d[0], b = j + d[1], c = k + d[2];
                if (a < 0 || b < 0 || c < 0 || a >= n || b >= n || c >= n) continue;
                const auto w = static_cast<std::size_t>(a + n * (b + n * c));
                if (dense[w] && component[w] < 0) {
                    component[w] = component[start];
                    queue.push_back(w);
                }
            }
        }
        sizes.push_back(size);
    }
    const VoxelPieces pieces(g);
    ASSERT_EQ(pieces.size(), sizes.size());
    std::sort(sizes.rbegin(), sizes.rend());
    for (std::size_t p = 0; p < sizes.size(); ++p) EXPECT_EQ(pieces.pieces()[p].voxels, sizes[p]);
    // Same partition: voxels share a piece exactly when the flood fill put them together.
    std::vector<std::uint32_t> piece_of_component(sizes.size(), VoxelPieces::none);
    for (std::size_t v = 0; v < dense.size(); ++v) {
        if (!dense[v]) continue;
        const int i = static_cast<int>(v % n), j = static_cast<int>((v / n) % n), k = static_cast<int>(v / (n * n));
        const std::uint32_t p = pieces.piece_at({i - 5, j, k + 3});
        auto& seen = piece_of_component[static_cast<std::size_t>(component[v])];
        if (seen == VoxelPieces::none) seen = p;
        EXPECT_EQ(p, seen);
    }
}

TEST(VoxelPieces, AreNumberedLargestFirstWithWorldBoxes)
{
    const LabelGrid g = three_cubes();
    const VoxelPieces pieces(g);
    ASSERT_EQ(pieces.size(), 3u);
    EXPECT_EQ(pieces.pieces()[0].voxels, 27u);
    EXPECT_EQ(pieces.pieces()[1].voxels, 8u);
    EXPECT_EQ(pieces.pieces()[2].voxels, 1u);
    EXPECT_DOUBLE_EQ(pieces.pieces()[1].volume_mm3, 64.0);
    EXPECT_TRUE(pieces.pieces()[1].min_mm.isApprox(Eigen::Vector3d(19, -1, -1)));
    EXPECT_TRUE(pieces.pieces()[1].max_mm.isApprox(Eigen::Vector3d(23, 3, 3)));
    EXPECT_EQ(pieces.piece_at({20, 0, 0}), 2u);
    EXPECT_EQ(pieces.piece_at({5, 0, 0}), VoxelPieces::none);
}

TEST(PieceSelection, KeepsLargestCountSizeSeedsAndHeld)
{
    PieceSelection s;
    s.components = PieceSelection::Components::largest;
    EXPECT_EQ(kept_voxels(s), 27u);
    s.components = PieceSelection::Components::count;
    s.count = 2;
    EXPECT_EQ(kept_voxels(s), 35u);
    s.count = 10; // more than there are: all
    EXPECT_EQ(kept_voxels(s), 36u);

    PieceSelection big;
    big.min_voxels = 5;
    EXPECT_EQ(kept_voxels(big), 35u);

    PieceSelection seeded; // the largest and the piece holding the point (40.4, 0.5, -0.5) mm
    seeded.components = PieceSelection::Components::largest;
    seeded.seeds_mm = {{40.4, 0.5, -0.5}};
    EXPECT_EQ(kept_voxels(seeded), 28u);

    PieceSelection held; // a box reaching the centres of the 2^3 cube's outer voxels (x = 20)
    held.components = PieceSelection::Components::held;
    held.held_boxes = {Eigen::AlignedBox3d(Eigen::Vector3d(15, 0, 0), Eigen::Vector3d(20, 1, 1))};
    EXPECT_EQ(kept_voxels(held), 8u);
    held.held_boxes = {Eigen::AlignedBox3d(Eigen::Vector3d(12, 0, 0), Eigen::Vector3d(18.5, 1, 1))}; // in the gap
    EXPECT_THROW((void)kept_voxels(held), vox::InputError);
}

TEST(PieceSelection, ExplainsASeedOutsideAndAnEmptyResult)
{
    PieceSelection s;
    s.seeds_mm = {{46.0, 0.0, 0.0}};
    try {
        (void)kept_voxels(s);
        FAIL() << "no error";
    } catch (const vox::InputError& e) {
        EXPECT_STREQ(e.what(), "cubes: seed_mm[0] (46, 0, 0) mm lies in no selected voxel; the nearest is 6 mm away, in piece 3");
    }
    PieceSelection too_big;
    too_big.min_voxels = 100;
    try {
        (void)kept_voxels(too_big);
        FAIL() << "no error";
    } catch (const vox::InputError& e) {
        EXPECT_STREQ(e.what(), "cubes: keeping every piece, of at least 100 voxels leaves no voxel (3 pieces: 1 (27 voxels), "
                               "2 (8 voxels), 3 (1 voxel))");
    }
}
