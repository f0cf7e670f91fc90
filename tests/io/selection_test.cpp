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
        EXPECT_STREQ(e.what(), "test.nii: the selection (label 42) holds no voxel; stored values present: 0, 3, 5");
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
