#include "io/nifti_writer.hpp"

#include "core/error.hpp"
#include "grid/label_grid.hpp"
#include "io/label_map_writer.hpp"
#include "io/selection.hpp"
#include "io/volume_reader.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <nifti2_io.h>

#include <cstddef>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

namespace fs = std::filesystem;
using namespace vox::io;

namespace {

/// A 4 x 3 x 2 int16 volume with a turned, shifted, anisotropic transform.
Volume sample_volume()
{
    Volume v;
    v.dims = {4, 3, 2};
    v.type = ScalarType::i16;
    const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    v.index_to_world = make_index_to_world({0.8, 0.9, 2.5}, turn, {-12.0, 40.5, 7.25});
    v.scale_slope = 2.0;
    v.scale_intercept = -1024.0;
    v.data.resize(24 * 2);
    for (std::int16_t n = 0; n < 24; ++n) {
        const auto value = static_cast<std::int16_t>(n * 37 - 300);
        std::memcpy(v.data.data() + 2 * n, &value, 2);
    }
    return v;
}

} // namespace

TEST(NiftiWriter, RoundTripsThroughOurReader)
{
    const Volume v = sample_volume();
    for (const char* name : {"written.nii", "written.nii.gz"}) {
        const fs::path path = fs::path(::testing::TempDir()) / name;
        write_nifti(v, path);
        const Volume back = read_volume(path.string());
        EXPECT_EQ(back.dims, v.dims) << name;
        EXPECT_EQ(back.type, v.type) << name;
        EXPECT_EQ(back.data, v.data) << name;
        EXPECT_DOUBLE_EQ(back.scale_slope, 2.0);
        EXPECT_DOUBLE_EQ(back.scale_intercept, -1024.0);
        EXPECT_LT((back.index_to_world - v.index_to_world).cwiseAbs().maxCoeff(), 1e-5) << name;
    }
}

TEST(NiftiWriter, LibniftiReadsTheSameVoxelsInRasWithAMatchingQform)
{
    // libnifti2 itself, not our reader: its sform and qform must both put voxel (i, j, k) at the
    // volume's LPS point with x and y negated.
    const Volume v = sample_volume();
    const fs::path path = fs::path(::testing::TempDir()) / "libnifti.nii.gz";
    write_nifti(v, path);
    nifti_image* nim = nifti_image_read(path.c_str(), 1);
    ASSERT_NE(nim, nullptr);
    EXPECT_EQ(nim->nx, 4);
    EXPECT_EQ(nim->ny, 3);
    EXPECT_EQ(nim->nz, 2);
    EXPECT_EQ(nim->datatype, DT_INT16);
    EXPECT_EQ(std::memcmp(nim->data, v.data.data(), v.data.size()), 0);
    for (const Eigen::Vector3d& ijk : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(3, 2, 1), Eigen::Vector3d(1, 0, 1)}) {
        const Eigen::Vector3d lps = (v.index_to_world * ijk.homogeneous()).head<3>();
        for (const nifti_dmat44& m : {nim->sto_xyz, nim->qto_xyz}) {
            Eigen::Vector3d ras;
            for (int r = 0; r < 3; ++r) ras[r] = m.m[r][0] * ijk.x() + m.m[r][1] * ijk.y() + m.m[r][2] * ijk.z() + m.m[r][3];
            EXPECT_NEAR(ras.x(), -lps.x(), 1e-4);
            EXPECT_NEAR(ras.y(), -lps.y(), 1e-4);
            EXPECT_NEAR(ras.z(), lps.z(), 1e-4);
        }
    }
    nifti_image_free(nim);
}

TEST(NiftiWriter, RefusesOtherNamesAndLeavesNothing)
{
    const fs::path path = fs::path(::testing::TempDir()) / "written.mha";
    EXPECT_THROW(write_nifti(sample_volume(), path), vox::InputError);
    EXPECT_FALSE(fs::exists(path));
}

TEST(NiftiWriter, ASformThatIsNotFiniteFallsBackToTheQformOrIsRefused)
{
    // The written file with a NaN put into its sform: the qform (which matches) places it, with a
    // warning; with the qform's code cleared too, nothing can place it and it is refused.
    const Volume v = sample_volume();
    const fs::path path = fs::path(::testing::TempDir()) / "nan_sform.nii";
    write_nifti(v, path);
    auto patch = [&](std::size_t offset, const void* bytes, std::size_t n) {
        std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
        f.seekp(static_cast<std::streamoff>(offset));
        f.write(static_cast<const char*>(bytes), static_cast<std::streamsize>(n));
    };
    const float nan = std::numeric_limits<float>::quiet_NaN();
    patch(offsetof(nifti_1_header, srow_x), &nan, sizeof nan);
    const Volume back = read_volume(path.string());
    EXPECT_LT((back.index_to_world - v.index_to_world).cwiseAbs().maxCoeff(), 1e-4);
    const std::int16_t unset = 0;
    patch(offsetof(nifti_1_header, qform_code), &unset, sizeof unset);
    try {
        (void)read_volume(path.string());
        FAIL() << "a file nothing can place was read";
    } catch (const vox::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("nan_sform.nii: its sform (the transform that places its voxels) is not finite"),
                  std::string::npos)
            << e.what();
    }
}

TEST(NiftiWriter, ALabelMapWrittenBackKeepsTheScansCodesAndQform)
{
    // A scan whose sform says MNI (code 4) and whose qform, aligned (code 2), sits 1.5 mm off it:
    // selected, then written back as a label map, the file says the same: both codes, the sform
    // and the qform as they were (ITK and Slicer pick one of them by its code).
    Volume scan = sample_volume();
    NiftiTransforms own;
    own.sform_code = NIFTI_XFORM_MNI_152;
    own.qform_code = NIFTI_XFORM_ALIGNED_ANAT;
    own.qform_ras = Eigen::Vector4d(-1.0, -1.0, 1.0, 1.0).asDiagonal() * scan.index_to_world;
    own.qform_ras(0, 3) += 1.5;
    scan.nifti = own;
    const fs::path in = fs::path(::testing::TempDir()) / "coded_scan.nii";
    write_nifti(scan, in);
    const Volume read = read_volume(in.string());
    ASSERT_TRUE(read.nifti.has_value());
    EXPECT_EQ(read.nifti->sform_code, NIFTI_XFORM_MNI_152);
    EXPECT_EQ(read.nifti->qform_code, NIFTI_XFORM_ALIGNED_ANAT);
    EXPECT_LT((read.nifti->qform_ras - own.qform_ras).cwiseAbs().maxCoeff(), 1e-4);

    Selection every;
    every.threshold_min = -1e9;
    const vox::grid::LabelGrid labels = select_voxels(read, every);
    const fs::path out = fs::path(::testing::TempDir()) / "coded_labels.nii";
    write_label_map(labels, out);
    nifti_image* back = nifti_image_read(out.c_str(), 0);
    ASSERT_NE(back, nullptr);
    EXPECT_EQ(back->sform_code, NIFTI_XFORM_MNI_152);
    EXPECT_EQ(back->qform_code, NIFTI_XFORM_ALIGNED_ANAT);
    const Eigen::Matrix4d sform_ras = Eigen::Vector4d(-1.0, -1.0, 1.0, 1.0).asDiagonal() * scan.index_to_world;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) {
            EXPECT_NEAR(back->sto_xyz.m[r][c], sform_ras(r, c), 1e-4) << r << ", " << c;
            EXPECT_NEAR(back->qto_xyz.m[r][c], own.qform_ras(r, c), 1e-4) << r << ", " << c;
        }
    nifti_image_free(back);
}
