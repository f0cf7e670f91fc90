#include "io/selection.hpp"

#include "core/error.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <string>

using namespace vox::io;

namespace {
Volume make_volume(const std::vector<std::int16_t>& values, double slope = 1.0, double intercept = 0.0)
{
    Volume v;
    v.source = "test.nii";
    v.dims = {static_cast<std::int64_t>(values.size()), 1, 1};
    v.type = ScalarType::i16;
    v.scale_slope = slope;
    v.scale_intercept = intercept;
    v.data.resize(values.size() * 2);
    std::memcpy(v.data.data(), values.data(), v.data.size());
    return v;
}
} // namespace

TEST(Selection, LabelsKeepTheirValue)
{
    Selection s;
    s.labels = {3, 7};
    const auto g = select_voxels(make_volume({0, 3, 5, 7, 7}), s);
    EXPECT_EQ(g.active_voxel_count(), 3u);
    EXPECT_EQ(g.get({1, 0, 0}), 3);
    EXPECT_EQ(g.get({2, 0, 0}), 0);
    EXPECT_EQ(g.get({4, 0, 0}), 7);
}

TEST(Selection, ThresholdAppliesToScaledValuesInclusiveAndGivesLabelOne)
{
    // Stored 0..4 with slope 100 and intercept -1024: -1024, -924, -824, -724, -624 HU.
    const Volume v = make_volume({0, 1, 2, 3, 4}, 100.0, -1024.0);
    const auto g = select_voxels(v, parse_threshold("-924:-724"));
    EXPECT_EQ(g.active_voxel_count(), 3u);
    EXPECT_EQ(g.get({1, 0, 0}), 1);
    EXPECT_EQ(g.get({3, 0, 0}), 1);
    EXPECT_EQ(select_voxels(v, parse_threshold("-800")).active_voxel_count(), 2u); // no upper bound
}

TEST(Selection, NoSelectionKeepsEveryNonZeroValue)
{
    const auto g = select_voxels(make_volume({0, -2, 9}), Selection{});
    EXPECT_EQ(g.active_voxel_count(), 2u);
    EXPECT_EQ(g.get({1, 0, 0}), -2);
}

TEST(Selection, EmptySelectionNamesTheFileAndTheValuesPresent)
{
    Selection s;
    s.labels = {42};
    try {
        (void)select_voxels(make_volume({0, 3, 5}), s);
        FAIL();
    } catch (const vox::InputError& e) {
        EXPECT_STREQ(e.what(), "test.nii: the selection (label 42) holds no voxel; stored values present (3 distinct, in 3 voxels; "
                               "smallest first, with their voxels): 0 (1), 3 (1), 5 (1)");
    }
}

TEST(Selection, AnEmptySelectionOfAScanOfManyValuesCountsTheSmallestAndAllOfThem)
{
    // 40 voxels of 20 values, each twice, the larger ones first in the file: the 12 smallest are
    // listed in order with their exact counts, and the 20 and 40 are totals, not a prefix.
    std::vector<std::int16_t> values;
    for (int k = 19; k >= 0; --k) values.push_back(static_cast<std::int16_t>(10 * k));
    for (int k = 0; k < 20; ++k) values.push_back(static_cast<std::int16_t>(10 * k));
    Selection s;
    s.labels = {7};
    try {
        (void)select_voxels(make_volume(values), s);
        FAIL();
    } catch (const vox::InputError& e) {
        EXPECT_STREQ(e.what(), "test.nii: the selection (label 7) holds no voxel; stored values present (20 distinct, in 40 voxels; "
                               "the smallest, with their voxels): 0 (2), 10 (2), 20 (2), 30 (2), 40 (2), 50 (2), 60 (2), 70 (2), "
                               "80 (2), 90 (2), 100 (2), 110 (2), ...");
    }
}

TEST(Selection, MalformedThresholds)
{
    EXPECT_THROW((void)parse_threshold("abc"), vox::InputError);
    EXPECT_THROW((void)parse_threshold("5:1"), vox::InputError);
    EXPECT_THROW((void)parse_threshold("1:"), vox::InputError);
    EXPECT_THROW((void)parse_threshold("nan"), vox::InputError);
}

TEST(Selection, LabelsMustFitInt32)
{
    // uint32 4000000000 is a whole number, but no 32-bit signed label: say so, not "not an integer".
    Volume v = make_volume({0, 0});
    v.type = ScalarType::u32;
    v.data.resize(8);
    const std::uint32_t values[2] = {1, 4000000000u};
    std::memcpy(v.data.data(), values, sizeof values);
    try {
        (void)select_voxels(v, Selection{});
        ADD_FAILURE() << "no error";
    } catch (const vox::InputError& e) {
        EXPECT_EQ(std::string(e.what()).rfind("test.nii: label 4000000000 does not fit a 32-bit signed label", 0), 0u)
            << e.what();
    }
    // The limits themselves fit; a fraction is still "not an integer label".
    const std::int32_t extremes[2] = {-2147483647 - 1, 2147483647};
    v.type = ScalarType::i32;
    std::memcpy(v.data.data(), extremes, sizeof extremes);
    const auto g = select_voxels(v, Selection{});
    EXPECT_EQ(g.get({0, 0, 0}), -2147483647 - 1);
    EXPECT_EQ(g.get({1, 0, 0}), 2147483647);
    v.type = ScalarType::f32;
    const float fractions[2] = {0.0f, 2.5f};
    std::memcpy(v.data.data(), fractions, sizeof fractions);
    try {
        (void)select_voxels(v, Selection{});
        ADD_FAILURE() << "no error";
    } catch (const vox::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("value 2.5 is not an integer label"), std::string::npos) << e.what();
    }
}
