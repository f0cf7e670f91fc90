#include "core/error.hpp"
#include "core/memory_limit.hpp"

#include <gtest/gtest.h>

TEST(MemoryLimit, RefusesAboveLimitAndOnOverflow)
{
    const auto saved = vox::memory_limit_bytes();
    vox::set_memory_limit_bytes(1u << 20);
    EXPECT_NO_THROW(vox::check_allocation("x", 1u << 18, 4));      // exactly 1 MiB
    EXPECT_THROW(vox::check_allocation("x", (1u << 18) + 1, 4), vox::InputError);
    EXPECT_THROW(vox::check_allocation("x", ~0ull / 2, 4), vox::InputError); // overflows 64 bits
    try {
        vox::check_allocation("scan.nii", 1u << 30, 2);
        FAIL();
    } catch (const vox::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("scan.nii: would need 2048 MiB"), std::string::npos) << e.what();
    }
    vox::set_memory_limit_bytes(saved);
}
