// The DICOM reader against series written by another implementation: pydicom (Debian's
// python3-pydicom) writes the bundled liver as CT slices (tests/io/write_dicom_series.py), and
// pydicom's own sample files give the compressed transfer syntaxes of one MR slice, encoded by
// other toolkits. GDCM itself only writes the JPEG lossless copy, which pydicom cannot encode.

#include "io/dicom_reader.hpp"
#include "io/object_import.hpp"
#include "io/volume_reader.hpp"

#include "test_support.hpp"

#include <gdcmImageChangeTransferSyntax.h>
#include <gdcmImageReader.h>
#include <gdcmImageWriter.h>

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

using namespace vox::io;
using vox::test::expect_refused;
using vox::test::ScratchDir;

namespace {

const std::string k_liver = VOX_SOURCE_DIR "/data/liver.inr.gz";

/// Runs the writer into `dir` with extra options (space-separated); a failure fails the test.
void write_series(const std::string& dir, const std::string& options)
{
    std::vector<std::string> args{k_liver, dir};
    std::istringstream words(options);
    for (std::string w; words >> w;) args.push_back(w);
    vox::test::run_python(VOX_SOURCE_DIR "/tests/io/write_dicom_series.py", args);
}

/// The folder of pydicom's sample files, as the installed package reports it.
std::string pydicom_samples()
{
    std::FILE* pipe = ::popen("/usr/bin/python3 -c \"import os, pydicom.data; "
                              "print(os.path.dirname(pydicom.data.get_testdata_file('MR_small.dcm')))\"",
                              "r");
    if (pipe == nullptr) return {};
    std::array<char, 4096> line{};
    const bool got = std::fgets(line.data(), static_cast<int>(line.size()), pipe) != nullptr;
    ::pclose(pipe);
    std::string dir = got ? std::string(line.data()) : std::string();
    while (!dir.empty() && (dir.back() == '\n' || dir.back() == '\r')) dir.pop_back();
    return dir;
}

/// What pydicom reads of the series `uid` in `dir` (searched with its sub-folders; "": every
/// DICOM image there): its slices sorted along their normal, the first one's position, the mean
/// gap between positions along the normal, the smallest gap over the largest, and every voxel's
/// value after the rescale (slope 1 and intercept 0 where a file has none), slice after slice.
struct PydicomSeries {
    Eigen::Vector3d first_position = Eigen::Vector3d::Zero();
    double mean_gap_mm = 0.0;
    double gap_ratio = 0.0;
    std::vector<double> values;
};

PydicomSeries read_with_pydicom(const std::string& dir, const std::string& uid)
{
    const ScratchDir scratch;
    const std::string out = scratch.path("values.txt");
    const std::string script =
        "import glob, sys, numpy as np, pydicom\n"
        "s = []\n"
        "for f in glob.glob(sys.argv[1] + '/**/*', recursive=True):\n"
        "    try: d = pydicom.dcmread(f)\n"
        "    except Exception: continue\n"
        "    if 'PixelData' in d and sys.argv[2] in ('', getattr(d, 'SeriesInstanceUID', '')): s.append(d)\n"
        "o = np.array(s[0].ImageOrientationPatient, float)\n"
        "n = np.cross(o[:3], o[3:])\n"
        "s.sort(key=lambda d: n @ np.array(d.ImagePositionPatient, float))\n"
        "along = np.array([n @ np.array(d.ImagePositionPatient, float) for d in s])\n"
        "gaps = np.diff(along)\n"
        "with open(sys.argv[3], 'w') as f:\n"
        "    f.write(' '.join(str(float(x)) for x in s[0].ImagePositionPatient) + '\\n')\n"
        "    f.write('%r %r\\n' % ((along[-1] - along[0]) / (len(s) - 1), gaps.min() / gaps.max()))\n"
        "    for d in s:\n"
        "        v = d.pixel_array * float(getattr(d, 'RescaleSlope', 1)) + float(getattr(d, 'RescaleIntercept', 0))\n"
        "        f.write(' '.join(str(float(x)) for x in v.ravel()) + '\\n')\n";
    (void)scratch.write("read.py", script);
    EXPECT_EQ(vox::test::run_python(scratch.path("read.py"), {dir, uid, out}), 0);
    PydicomSeries r;
    std::ifstream in(out);
    in >> r.first_position.x() >> r.first_position.y() >> r.first_position.z() >> r.mean_gap_mm >> r.gap_ratio;
    for (double value = 0.0; in >> value;) r.values.push_back(value);
    return r;
}

/// Voxels of `v` whose scaled value differs from pydicom's (all of them when the counts differ).
std::int64_t differences(const Volume& v, const PydicomSeries& p)
{
    if (static_cast<std::int64_t>(p.values.size()) != v.voxel_count()) return v.voxel_count();
    std::int64_t different = 0;
    for (std::int64_t i = 0; i < v.voxel_count(); ++i) different += p.values[static_cast<std::size_t>(i)] != v.scaled(i);
    return different;
}

/// Every voxel's scaled value equal, slices [0, slices) of `expected` against `got`.
void expect_same_values(const Volume& expected, const Volume& got, std::int64_t slices)
{
    const std::int64_t n = expected.dims[0] * expected.dims[1] * slices;
    std::int64_t different = 0;
    for (std::int64_t i = 0; i < n; ++i)
        if (expected.scaled(i) != got.scaled(i)) ++different;
    EXPECT_EQ(different, 0) << "of " << n << " voxels";
}

/// The writer's --rotate-deg 30: 30 degrees about (1, 2, 3).
Eigen::Matrix3d writer_rotation_30()
{
    return Eigen::AngleAxisd(30.0 * M_PI / 180.0, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
}

/// The first 24 slices of the liver, written turned by --rotate-deg 30 with `options`, read back:
/// the INR's size and values.
Volume read_turned_liver(const ScratchDir& scratch, const std::string& name, const std::string& options, const Volume& inr)
{
    const std::string dir = scratch.path(name);
    write_series(dir, "--rotate-deg 30 --shuffle --slices 24 " + options);
    Volume dicom = read_dicom(dir);
    EXPECT_EQ(dicom.dims, (std::array<std::int64_t, 3>{inr.dims[0], inr.dims[1], 24}));
    if (dicom.dims[2] == 24) expect_same_values(inr, dicom, 24);
    return dicom;
}

} // namespace

TEST(DicomReader, TheLiverWrittenOutOfOrderImportsAsTheInrFileDoes)
{
    // File names shuffled and instance numbers reversed: only the positions order the slices.
    const ScratchDir scratch;
    const std::string dir = scratch.path("liver");
    write_series(dir, "--shuffle");
    const Volume inr = read_volume(k_liver);
    const Volume dicom = read_dicom(dir);
    ASSERT_EQ(dicom.dims, inr.dims);
    EXPECT_TRUE(dicom.index_to_world.isApprox(inr.index_to_world, 1e-9)) << dicom.index_to_world;
    EXPECT_EQ(dicom.type, ScalarType::i16);
    expect_same_values(inr, dicom, inr.dims[2]);

    // Through the one import entry: the same labelled voxels at the same world points.
    ImportOptions liver;
    liver.selection.labels = {255};
    const vox::grid::LabelGrid a = import_object(k_liver, liver), b = import_object(dir, liver);
    EXPECT_EQ(b.active_voxel_count(), 3160496u);
    EXPECT_EQ(b.index_bounds().min, a.index_bounds().min);
    EXPECT_EQ(b.index_bounds().max, a.index_bounds().max);
    EXPECT_TRUE(b.index_to_world().isApprox(a.index_to_world(), 1e-9));
    EXPECT_EQ(import_object(dir, {}).label_histogram(), import_object(k_liver, {}).label_histogram());
}

TEST(DicomReader, AnObliqueSeriesKeepsItsOrientationInWorldMillimetres)
{
    const ScratchDir scratch;
    const Volume inr = read_volume(k_liver);
    const Volume dicom = read_turned_liver(scratch, "oblique", "--rescale", inr);
    // Columns of the index-to-world map are the rotated axes times the spacings, the origin the INR's.
    const Eigen::Matrix3d r = writer_rotation_30();
    Eigen::Matrix4d expected = Eigen::Matrix4d::Identity();
    expected.topLeftCorner<3, 3>() = r * inr.index_to_world.topLeftCorner<3, 3>();
    expected.topRightCorner<3, 1>() = inr.index_to_world.topRightCorner<3, 1>();
    EXPECT_TRUE(dicom.index_to_world.isApprox(expected, 1e-8)) << dicom.index_to_world << "\nexpected\n" << expected;
    // Stored 2 v + 1000: only the rescale (slope 0.5, intercept -500) gives the values back.
    EXPECT_EQ(dicom.scale_slope, 0.5);
    EXPECT_EQ(dicom.scale_intercept, -500.0);
}

TEST(DicomReader, RleCompressedSlicesDecodeToTheSameValues)
{
    const ScratchDir scratch;
    const std::string dir = scratch.path("rle");
    write_series(dir, "--rle --slices 12");
    const Volume inr = read_volume(k_liver);
    const Volume dicom = read_dicom(dir);
    ASSERT_EQ(dicom.dims[2], 12);
    expect_same_values(inr, dicom, 12);
}

TEST(DicomReader, CompressedTransferSyntaxesOfPacsExportsDecodeAlike)
{
    // pydicom's samples: one MR slice, uncompressed and as other toolkits encoded it.
    const std::string samples = pydicom_samples();
    ASSERT_FALSE(samples.empty()) << "python3-pydicom is not installed (scripts/install-deps.sh installs it)";
    const Volume reference = read_dicom(samples + "/MR_small.dcm");
    ASSERT_EQ(reference.dims, (std::array<std::int64_t, 3>{64, 64, 1}));
    for (const char* name : {"MR_small_RLE.dcm", "MR_small_jp2klossless.dcm", "MR_small_jpeg_ls_lossless.dcm",
                             "MR_small_bigendian.dcm", "MR_small_implicit.dcm"}) {
        SCOPED_TRACE(name);
        const Volume v = read_dicom(samples + "/" + name);
        ASSERT_EQ(v.dims, reference.dims);
        EXPECT_TRUE(v.index_to_world.isApprox(reference.index_to_world, 1e-12));
        expect_same_values(reference, v, 1);
    }

    // JPEG lossless (process 14, selection value 1), which pydicom cannot write: GDCM transcodes.
    const ScratchDir scratch;
    gdcm::ImageReader reader;
    reader.SetFileName((samples + "/MR_small.dcm").c_str());
    ASSERT_TRUE(reader.Read());
    gdcm::ImageChangeTransferSyntax change;
    change.SetTransferSyntax(gdcm::TransferSyntax::JPEGLosslessProcess14_1);
    change.SetInput(reader.GetImage());
    ASSERT_TRUE(change.Change());
    gdcm::ImageWriter writer;
    writer.SetFileName(scratch.path("jpeg_lossless.dcm").c_str());
    writer.SetFile(reader.GetFile());
    writer.SetImage(change.GetOutput());
    ASSERT_TRUE(writer.Write());
    expect_same_values(reference, read_dicom(scratch.path("jpeg_lossless.dcm")), 1);
}

TEST(DicomReader, AFolderOfSeveralSeriesIsListedAndOneIsPickedByNumberOrUid)
{
    const ScratchDir scratch;
    write_series(scratch.path("two/a"), "--slices 60 --series-number 7 --description arterial");
    write_series(scratch.path("two/b"), "--slices 6 --series-number 2 --description venous --shuffle");
    std::ofstream(scratch.path("two/notes.txt")) << "not a DICOM file\n"; // skipped, as a DICOMDIR or notes would be
    const std::string dir = scratch.path("two");
    const std::vector<DicomSeries> all = list_dicom_series(dir);
    ASSERT_EQ(all.size(), 2u);
    EXPECT_EQ(all[0].number, 1);
    EXPECT_EQ(all[0].description, "venous"); // ordered by SeriesNumber
    EXPECT_EQ(all[0].size, (std::array<std::int64_t, 3>{438, 353, 6}));
    EXPECT_EQ(all[1].description, "arterial");
    EXPECT_EQ(all[1].modality, "CT");

    expect_refused([&] { (void)read_dicom(dir); }, dir, "holds 2 series");
    EXPECT_EQ(read_dicom(dir, "2").dims[2], 60);
    EXPECT_EQ(read_dicom(dir, all[0].uid).dims[2], 6);
    expect_refused([&] { (void)read_dicom(dir, "3"); }, dir, "has no series 3");
    ImportOptions pick;
    pick.series = "2";
    pick.selection.labels = {255};
    const Volume inr = read_volume(k_liver);
    std::uint64_t liver_in_60 = 0;
    for (std::int64_t n = 0; n < inr.dims[0] * inr.dims[1] * 60; ++n) liver_in_60 += inr.stored(n) == 255.0;
    ASSERT_GT(liver_in_60, 0u);
    EXPECT_EQ(import_object(dir, pick).active_voxel_count(), liver_in_60);
    pick.series = "1";
    expect_refused([&] { (void)import_object(k_liver, pick); }, k_liver, "--series picks a series of a DICOM folder");
}

TEST(DicomReader, PositionsRoundedByTheScannerAreReadOnTheirEvenGrid)
{
    // Oblique slices 1.3333 mm apart whose positions are written rounded to 0.1 mm, as scanners
    // write them: neighbours' gaps vary from about 1.2 to 1.5 mm (more than 10 %), yet every slice
    // lies within 0.09 mm of an even grid. The volume is the INR's, voxel for voxel, on that grid.
    const ScratchDir scratch;
    const Volume inr = read_volume(k_liver);
    const Volume dicom = read_turned_liver(scratch, "rounded", "--round-mm 0.1", inr);
    const Eigen::Matrix3d r = writer_rotation_30();
    const Eigen::Vector3d slice_step = dicom.index_to_world.block<3, 1>(0, 2);
    EXPECT_NEAR(slice_step.norm(), inr.index_to_world(2, 2), 0.02); // the positions' mean gap is 4/3 mm
    EXPECT_LT((slice_step.normalized() - r.col(2)).norm(), 1e-4) << slice_step.transpose();
    // The grid's first voxel within the rounding of where the writer put it.
    EXPECT_LT((dicom.index_to_world.block<3, 1>(0, 3) - inr.index_to_world.block<3, 1>(0, 3)).norm(), 0.09);

    // Gaps of 1.33 mm with one position 0.2 mm off (15 %): a defect, not rounding.
    const std::string off = scratch.path("off");
    write_series(off, "--slices 12 --round-mm 0.4");
    expect_refused([&] { (void)read_dicom(off); }, off, "off the even grid, more than 10 % of the spacing");
}

TEST(DicomReader, IrregularSeriesAreRefusedWithWhatWasFound)
{
    const ScratchDir scratch;
    write_series(scratch.path("missing"), "--slices 20 --drop-slice 8");
    expect_refused([&] { (void)read_dicom(scratch.path("missing")); }, scratch.path("missing"),
                   "uneven slice spacing: 2.66666 mm between");
    write_series(scratch.path("twice"), "--slices 20 --duplicate-slice 5");
    expect_refused([&] { (void)read_dicom(scratch.path("twice")); }, scratch.path("twice"), "has two slices at");
    write_series(scratch.path("tilted"), "--slices 20 --tilt-deg 12");
    expect_refused([&] { (void)read_dicom(scratch.path("tilted")); }, scratch.path("tilted"),
                   "stacked 12 degrees off their normal (gantry tilt)");
    std::filesystem::create_directories(scratch.path("empty"));
    expect_refused([&] { (void)read_dicom(scratch.path("empty")); }, scratch.path("empty"), "is an empty folder");
    std::filesystem::create_directories(scratch.path("plain"));
    (void)scratch.write("plain/readme.txt", "nothing here\n");
    expect_refused([&] { (void)read_dicom(scratch.path("plain")); }, scratch.path("plain"), "holds no DICOM image");
    expect_refused([&] { (void)read_dicom(scratch.path("nowhere")); }, scratch.path("nowhere"), "no such file or folder");
}

TEST(DicomReader, AScannerExportBesideOtherSeriesAndADamagedDicomdirReadsAsPydicomReadsIt)
{
    // pydicom's dicomdirtests: 91 files of three patients (CR, CT, MR series, DICOMDIRs, one of
    // which, DICOMDIR-nooffset, makes GDCM abort: skipped with a warning). Its gated CT series (5
    // slices, instance numbers falling as the position rises) against pydicom's own reading:
    // slices sorted along the normal, Hounsfield units from the rescale.
    const std::string samples = pydicom_samples();
    ASSERT_FALSE(samples.empty());
    const std::string dir = samples + "/dicomdirtests";
    const std::string uid = "1.3.6.1.4.1.5962.1.1.0.0.0.1194734704.16302.0.6";
    const std::vector<DicomSeries> all = list_dicom_series(dir);
    EXPECT_EQ(all.size(), 13u);
    const Volume v = read_dicom(dir, uid);
    ASSERT_EQ(v.dims, (std::array<std::int64_t, 3>{16, 16, 5}));

    const PydicomSeries p = read_with_pydicom(dir, uid);
    EXPECT_TRUE((v.index_to_world.topRightCorner<3, 1>().isApprox(p.first_position, 1e-9)));
    EXPECT_EQ(differences(v, p), 0);
}

namespace {
const std::string k_ge_rounded = VOX_SOURCE_DIR "/tests/data/dicom_ge_rounded";
} // namespace

TEST(DicomReader, ARealSeriesWithRoundedPositionsReadsOnItsEvenGridAsPydicomReadsIt)
{
    // A GE scanner's oblique MR series (tests/data/README.md) whose positions it rounded to 0.1 mm:
    // gaps of 6.958 - 7.071 mm. It lists as importable and reads with pydicom's voxels, on the
    // even grid whose step is the positions' mean gap.
    const std::vector<DicomSeries> listed = list_dicom_series(k_ge_rounded);
    ASSERT_EQ(listed.size(), 1u);
    EXPECT_EQ(listed[0].problem, "");
    EXPECT_EQ(listed[0].size, (std::array<std::int64_t, 3>{256, 256, 20}));
    const Volume v = read_dicom(k_ge_rounded);
    ASSERT_EQ(v.dims, (std::array<std::int64_t, 3>{256, 256, 20}));

    const PydicomSeries p = read_with_pydicom(k_ge_rounded, "");
    EXPECT_LT(p.gap_ratio, 0.985) << "the gaps are uneven beyond 1 %: what this series is here for";
    EXPECT_NEAR((v.index_to_world.block<3, 1>(0, 2).norm()), p.mean_gap_mm, 0.02);
    EXPECT_EQ(differences(v, p), 0);
}

TEST(DicomReader, ARealSeriesWithASliceTakenOutIsStillRefused)
{
    // The same rounded series without its tenth slice: a real gap of 14 mm, not rounding.
    const ScratchDir scratch;
    const std::string dir = scratch.path("gap");
    std::filesystem::create_directories(dir);
    for (const auto& f : std::filesystem::directory_iterator(k_ge_rounded))
        if (f.path().extension() == ".dcm" && f.path().filename() != "brain_010.dcm")
            std::filesystem::copy_file(f.path(), std::filesystem::path(dir) / f.path().filename());
    expect_refused([&] { (void)read_dicom(dir); }, dir, "has uneven slice spacing: 1");
    const std::vector<DicomSeries> listed = list_dicom_series(dir); // listed, with the reason
    ASSERT_EQ(listed.size(), 1u);
    EXPECT_NE(listed[0].problem.find("(a missing slice?"), std::string::npos) << listed[0].problem;
}
