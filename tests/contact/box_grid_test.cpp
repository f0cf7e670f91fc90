// The broad phase's grid of boxes against brute force: every two overlapping boxes found once,
// every box meeting a query found, for boxes packed together and for one flung a kilometre away
// (which makes the grid merge its cells).

#include "contact/box_grid.hpp"

#include <gtest/gtest.h>

#include <random>
#include <set>
#include <utility>

namespace vox::contact {
namespace {

std::vector<Eigen::AlignedBox3d> random_boxes(std::mt19937& rng, std::size_t n, bool one_far)
{
    std::uniform_real_distribution<double> at(0.0, 40.0), size(0.1, 6.0);
    std::vector<Eigen::AlignedBox3d> boxes;
    for (std::size_t i = 0; i < n; ++i) {
        const Eigen::Vector3d low(at(rng), at(rng), at(rng));
        boxes.emplace_back(low, low + Eigen::Vector3d(size(rng), size(rng), size(rng)));
    }
    if (one_far) boxes.emplace_back(Eigen::Vector3d(1e6, -3.0, 2.0), Eigen::Vector3d(1e6 + 4.0, 1.0, 5.0));
    return boxes;
}

TEST(BoxGrid, FindsEveryOverlappingPairOnceAndEveryBoxAQueryMeets)
{
    std::mt19937 rng(3);
    for (int trial = 0; trial < 6; ++trial) {
        const std::vector<Eigen::AlignedBox3d> boxes = random_boxes(rng, 300, trial % 2 == 1);
        const BoxGrid grid(boxes, 4.0);
        std::set<std::pair<std::uint32_t, std::uint32_t>> expected, found;
        for (std::uint32_t i = 0; i < boxes.size(); ++i)
            for (std::uint32_t j = i + 1; j < boxes.size(); ++j)
                if (boxes[i].intersects(boxes[j])) expected.emplace(i, j);
        std::size_t calls = 0;
        grid.overlapping_pairs([&](std::uint32_t i, std::uint32_t j) {
            ++calls;
            EXPECT_LT(i, j);
            found.emplace(i, j);
        });
        EXPECT_EQ(found, expected) << "trial " << trial;
        EXPECT_EQ(calls, expected.size()) << "each pair once";

        for (const Eigen::AlignedBox3d& query : random_boxes(rng, 40, trial % 2 == 1)) {
            std::set<std::uint32_t> near;
            grid.near(query, [&](std::uint32_t i) { near.insert(i); });
            for (std::uint32_t i = 0; i < boxes.size(); ++i)
                EXPECT_TRUE(!boxes[i].intersects(query) || near.count(i)) << "trial " << trial << ": box " << i << " meets the query";
        }
        std::size_t none = 0;
        grid.near(Eigen::AlignedBox3d(Eigen::Vector3d::Constant(-500.0), Eigen::Vector3d::Constant(-400.0)), [&](std::uint32_t) { ++none; });
        EXPECT_EQ(none, 0u) << "a query outside every cell meets nothing";
    }
    const BoxGrid empty({}, 1.0);
    std::size_t calls = 0;
    empty.near(Eigen::AlignedBox3d(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones()), [&](std::uint32_t) { ++calls; });
    empty.overlapping_pairs([&](std::uint32_t, std::uint32_t) { ++calls; });
    EXPECT_EQ(calls, 0u);
}

} // namespace
} // namespace vox::contact
