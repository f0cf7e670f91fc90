#include "io/skull_phantom.hpp"

#include "core/error.hpp"
#include "io/scene.hpp"
#include "io/selection.hpp"
#include "io/volume_reader.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cstring>
#include <nlohmann/json.hpp>

using namespace vox::io;

namespace {

double hu_at(const Volume& v, const Eigen::Vector3d& world_mm)
{
    const Eigen::Vector3d ijk = (v.index_to_world.inverse() * world_mm.homogeneous()).head<3>();
    const std::int64_t i = std::lround(ijk.x()), j = std::lround(ijk.y()), k = std::lround(ijk.z());
    return v.scaled(i + v.dims[0] * (j + v.dims[1] * k));
}

} // namespace

TEST(SkullPhantom, BundledFileIsWhatTheGeneratorMakes)
{
    const Volume made = make_skull_phantom({});
    const Volume bundled = read_volume(VOX_SOURCE_DIR "/data/skull_phantom.nii.gz");
    EXPECT_EQ(bundled.dims, made.dims);
    EXPECT_EQ(bundled.type, ScalarType::i16);
    EXPECT_LT((bundled.index_to_world - made.index_to_world).cwiseAbs().maxCoeff(), 1e-6);
    EXPECT_TRUE(bundled.data == made.data) << "regenerate it: voxsculpt phantom skull -o data/skull_phantom.nii.gz";
}

TEST(SkullPhantom, HasCtValuesAndAnisotropicVoxels)
{
    const Volume v = make_skull_phantom({});
    EXPECT_EQ(v.dims, (std::array<std::int64_t, 3>{200, 240, 80}));
    EXPECT_NEAR(v.spacing().z() / v.spacing().x(), 1.5 / 0.9, 1e-12);
    EXPECT_EQ(hu_at(v, {90, 110, 40}), skull_hu::brain);  // the head's centre
    EXPECT_EQ(hu_at(v, {1, 1, 118}), skull_hu::air);      // a corner of the field
    // Straight back from the centre (+y; points at voxel centres): brain, the inner table, diploe,
    // the outer table, scalp. The vault's outer surface there is 84 mm behind the centre (y = 194)
    // and 7.5 mm thick, its tables 1.5 mm.
    EXPECT_EQ(hu_at(v, {90, 185.4, 40.5}), skull_hu::brain);
    EXPECT_EQ(hu_at(v, {90, 187.2, 40.5}), skull_hu::cortical);
    EXPECT_EQ(hu_at(v, {90, 189.9, 40.5}), skull_hu::diploe);
    EXPECT_EQ(hu_at(v, {90, 193.5, 40.5}), skull_hu::cortical);
    EXPECT_EQ(hu_at(v, {90, 196.2, 40.5}), skull_hu::soft);
}

TEST(SkullPhantom, BoneThresholdCatchesSkullHolderAndLooseFragmentsAsSeparatePieces)
{
    Selection bone;
    bone.threshold_min = 226.0;
    bone.threshold_max = 3071.0;
    const vox::grid::LabelGrid labels = select_voxels(make_skull_phantom({}), bone);
    const vox::grid::VoxelPieces pieces(labels);
    ASSERT_GE(pieces.size(), 12u);
    const auto& skull = pieces.pieces()[0];
    const auto& holder = pieces.pieces()[1];
    // The skull spans its outer ellipsoid's width (2 x 68 mm) across x; the holder curves behind
    // it (+y) and below the head's centre (z = 40).
    EXPECT_NEAR(skull.max_mm.x() - skull.min_mm.x(), 136.0, 3.0);
    EXPECT_GT(holder.max_mm.y(), skull.max_mm.y() + 10.0);
    EXPECT_LT(holder.max_mm.z(), 40.0);
    EXPECT_GT(holder.voxels, 5000u);
    for (std::size_t p = 2; p < pieces.size(); ++p) EXPECT_LT(pieces.pieces()[p].voxels, 200u) << "piece " << p + 1;
}

TEST(SkullPhantom, ThresholdBandsGiveBoneAndSoftTissueTheirOwnLabels)
{
    // Bone [226, 3071] -> 1, soft tissue [0, 100] -> 2 (scalp, brain, neck); air and the
    // holder's foam are in no band. A scene gives each label its own material.
    nlohmann::json doc = nlohmann::json::parse(R"({
        "object": {"select": {"threshold_bands": [{"range": [226, 3071], "label": 1}, {"range": [0, 100], "label": 2}]}},
        "materials": {"labels": {"1": {"youngs_modulus_pa": 1.5e10}, "2": {"youngs_modulus_pa": 3e4}}}
    })");
    doc["object"]["volume"] = VOX_SOURCE_DIR "/data/skull_phantom.nii.gz";
    const Scene scene = parse_scene(doc, VOX_SOURCE_DIR "/data", "bands.json");
    ASSERT_EQ(scene.object.select.bands.size(), 2u);
    const vox::grid::LabelGrid labels = select_voxels(make_skull_phantom({}), scene.object.select);
    const auto histogram = labels.label_histogram();
    ASSERT_EQ(histogram.size(), 2u);
    Selection bone;
    bone.threshold_min = 226.0;
    bone.threshold_max = 3071.0;
    EXPECT_EQ(histogram.at(1), select_voxels(make_skull_phantom({}), bone).active_voxel_count());
    EXPECT_GT(histogram.at(2), histogram.at(1)) << "more soft tissue than bone in a head";
    EXPECT_EQ(labels.get(vox::grid::Coord(100, 122, 27)), 2) << "brain at the head's centre";

    // A label of 0, a band the wrong way round and a material for a label no band gives are refused.
    nlohmann::json bad = doc;
    bad["object"]["select"]["threshold_bands"][1]["label"] = 0;
    EXPECT_THROW((void)parse_scene(bad, VOX_SOURCE_DIR "/data", "bands.json"), vox::InputError);
    bad = doc;
    bad["object"]["select"]["threshold_bands"][1]["range"] = {100, 0};
    EXPECT_THROW((void)parse_scene(bad, VOX_SOURCE_DIR "/data", "bands.json"), vox::InputError);
    bad = doc;
    bad["materials"]["labels"]["3"] = {{"youngs_modulus_pa", 1e5}};
    try {
        (void)parse_scene(bad, VOX_SOURCE_DIR "/data", "bands.json");
        FAIL() << "no error";
    } catch (const vox::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("label 3 is not in object.select.threshold_bands (1, 2)"), std::string::npos) << e.what();
    }
}
