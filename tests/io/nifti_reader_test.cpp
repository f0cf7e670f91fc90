#include "io/volume_reader.hpp"

#include "core/error.hpp"
#include "io/test_volume_writers.hpp"

#include <gtest/gtest.h>
#include <nifti2_io.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>

namespace fs = std::filesystem;
using namespace vox::io;
using vox::test::world;

namespace {

/// A 3 x 2 x 2 int16 NIfTI-1 file written by libnifti2 itself; `setup` fills the header fields.
std::string write_nifti_file(const std::string& name, const std::function<void(nifti_image&)>& setup)
{
    const int64_t dims[8] = {3, 3, 2, 2, 1, 1, 1, 1};
    nifti_image* nim = nifti_make_new_nim(dims, DT_INT16, 1);
    auto* data = static_cast<std::int16_t*>(nim->data);
    for (int n = 0; n < 12; ++n) data[n] = static_cast<std::int16_t>(n * 10 - 50);
    nim->nifti_type = NIFTI_FTYPE_NIFTI1_1;
    setup(*nim);
    const std::string path = (fs::path(::testing::TempDir()) / name).string();
    nifti_set_filenames(nim, path.c_str(), 0, 1);
    nifti_image_write(nim);
    nifti_image_free(nim);
    return path;
}

} // namespace

TEST(NiftiReader, QformRotationIsConvertedFromRasToLps)
{
    // qform: 90 degrees about z (quaternion a = cos 45, d = sin 45), spacing 2 3 4, offset (10 20 30).
    const std::string path = write_nifti_file("qform.nii", [](nifti_image& nim) {
        nim.pixdim[1] = nim.dx = 2;
        nim.pixdim[2] = nim.dy = 3;
        nim.pixdim[3] = nim.dz = 4;
        nim.qform_code = NIFTI_XFORM_SCANNER_ANAT;
        nim.sform_code = 0;
        nim.quatern_b = 0;
        nim.quatern_c = 0;
        nim.quatern_d = std::sqrt(0.5);
        nim.qoffset_x = 10;
        nim.qoffset_y = 20;
        nim.qoffset_z = 30;
        nim.qfac = 1;
    });
    const Volume v = read_volume(path);
    EXPECT_EQ(v.dims, (std::array<std::int64_t, 3>{3, 2, 2}));
    // In RAS, index axis i points along +y: voxel (1,0,0) is at (10, 22, 30); LPS negates x and y.
    EXPECT_TRUE(world(v, 0, 0, 0).isApprox(Eigen::Vector3d(-10, -20, 30), 1e-6));
    EXPECT_TRUE(world(v, 1, 0, 0).isApprox(Eigen::Vector3d(-10, -22, 30), 1e-6));
    EXPECT_TRUE(world(v, 0, 1, 0).isApprox(Eigen::Vector3d(-7, -20, 30), 1e-6));
    EXPECT_TRUE(world(v, 0, 0, 1).isApprox(Eigen::Vector3d(-10, -20, 34), 1e-6));
    EXPECT_EQ(v.stored(0), -50.0);
    EXPECT_EQ(v.stored(11), 60.0);
}

TEST(NiftiReader, SformTakesPrecedenceAndKeepsShear)
{
    const std::string path = write_nifti_file("sform.nii.gz", [](nifti_image& nim) {
        nim.qform_code = NIFTI_XFORM_SCANNER_ANAT; // identity qform, overridden by the sform
        nim.sform_code = NIFTI_XFORM_ALIGNED_ANAT;
        const double s[3][4] = {{1.5, 0.25, 0, -5}, {0, 2, 0, 7}, {0, 0, 0.5, 1}};
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c) nim.sto_xyz.m[r][c] = s[r][c];
    });
    const Volume v = read_volume(path);
    EXPECT_TRUE(world(v, 0, 0, 0).isApprox(Eigen::Vector3d(5, -7, 1), 1e-6));
    EXPECT_TRUE(world(v, 2, 1, 1).isApprox(Eigen::Vector3d(-(3 + 0.25 - 5), -(2 + 7), 1.5), 1e-6));
}

TEST(NiftiReader, SlopeAndInterceptScaleValues)
{
    const std::string path = write_nifti_file("scaled.nii", [](nifti_image& nim) {
        nim.scl_slope = 2;
        nim.scl_inter = -1024;
    });
    const Volume v = read_volume(path);
    EXPECT_EQ(v.stored(1), -40.0);
    EXPECT_EQ(v.scaled(1), -1104.0);
}

TEST(NiftiReader, MissingFileAndGarbageAreInputErrors)
{
    EXPECT_THROW((void)read_volume("/nonexistent/scan.nii"), vox::InputError);
    const std::string junk = (fs::path(::testing::TempDir()) / "junk.nii").string();
    std::ofstream(junk) << "this is not a nifti header";
    try {
        (void)read_volume(junk);
        FAIL();
    } catch (const vox::InputError& e) {
        EXPECT_EQ(std::string(e.what()).rfind(junk + ": ", 0), 0u) << e.what();
    }
}
