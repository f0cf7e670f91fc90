// What every reader checks first (src/io/file_bytes.cpp, check_input_file): a missing path, a
// folder, an empty file, each said in the same words whatever the format, and gzip errors that name
// the file once.

#include "io/file_bytes.hpp"

#include "core/error.hpp"
#include "io/object_import.hpp"
#include "io/test_volume_writers.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace vox::io {
namespace {

/// Every extension `voxsculpt import` reads: volumes, the label grid, meshes.
const char* const k_extensions[] = {".inr", ".inr.gz", ".nii", ".nii.gz", ".mhd", ".mha", ".nrrd", ".nhdr",
                                    ".vdb", ".obj", ".ply", ".stl", ".off"};

void expect_import_refused(const std::string& path, const std::string& problem)
{
    SCOPED_TRACE(path);
    EXPECT_EQ(test::error_of([&] { (void)import_object(path, ImportOptions{}); }), path + ": " + problem);
}

TEST(InputFile, MissingFolderAndEmptyAreSaidTheSameWayByEveryReader)
{
    const test::ScratchDir dir;
    for (const char* ext : k_extensions) {
        expect_import_refused(dir.path(std::string("absent") + ext), "no such file");
        const std::string folder = dir.path(std::string("folder") + ext);
        std::filesystem::create_directory(folder);
        expect_import_refused(folder, "is a folder, not a file");
        expect_import_refused(dir.write(std::string("empty") + ext, ""), "is empty");
    }
}

TEST(InputFile, CheckInputFile)
{
    const test::ScratchDir dir;
    EXPECT_NO_THROW(check_input_file(dir.write("x.bin", "x")));
    test::expect_refused([&] { check_input_file(dir.path("none")); }, dir.path("none"), ": no such file");
    test::expect_refused([&] { check_input_file(dir.path("none/x")); }, dir.path("none/x"), ": no such file");
    test::expect_refused([&] { check_input_file(dir.root().string()); }, dir.root().string(),
                         ": is a folder, not a file");
    test::expect_refused([&] { check_input_file("/dev/null"); }, "/dev/null", ": is not a regular file");
}

TEST(InputFile, GzipErrorsNameTheFileOnce)
{
    // zlib puts the file name in front of its message; ours starts with it already.
    const test::ScratchDir dir;
    const std::string zipped = test::gzip(std::string(1000, 'x'));
    const std::string path = dir.write("cut.inr.gz", zipped.substr(0, zipped.size() / 2));
    const std::string message = test::error_of([&] { (void)read_file_bytes(path); });
    EXPECT_EQ(message.rfind(path + ": corrupt or truncated gzip data", 0), 0u) << message;
    EXPECT_EQ(message.find(path, 1), std::string::npos) << message;
    EXPECT_EQ(message.find("cut.inr.gz", path.size()), std::string::npos) << message;
    const std::string nothing = dir.write("nothing.gz", test::gzip(""));
    EXPECT_EQ(test::error_of([&] { (void)read_file_bytes(nothing); }),
              nothing + ": is empty once decompressed (gzip of no data)");
}

} // namespace
} // namespace vox::io
