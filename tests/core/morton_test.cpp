#include "core/morton.hpp"

#include <gtest/gtest.h>

TEST(Morton, MatchesThePapersEquationAndRoundTrips)
{
    // Equation 6: Idx = sum_l (4 z_l + 2 y_l + x_l) 8^l, written out bit by bit.
    for (std::uint32_t x = 0; x < 16; ++x)
        for (std::uint32_t y = 0; y < 16; ++y)
            for (std::uint32_t z = 0; z < 16; ++z) {
                std::uint64_t expect = 0;
                for (int l = 0; l < 4; ++l)
                    expect += std::uint64_t(4 * ((z >> l) & 1) + 2 * ((y >> l) & 1) + ((x >> l) & 1)) << (3 * l);
                const std::uint64_t code = vox::morton_encode(x, y, z);
                ASSERT_EQ(code, expect);
                EXPECT_EQ(vox::morton_decode_axis(code, 0), x);
                EXPECT_EQ(vox::morton_decode_axis(code, 1), y);
                EXPECT_EQ(vox::morton_decode_axis(code, 2), z);
            }
    EXPECT_EQ(vox::morton_decode_axis(vox::morton_encode(0x1fffff, 12345, 0x100000), 2), 0x100000u);
}
