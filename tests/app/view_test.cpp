// The interactive viewer, run as CI runs it: in a window on a virtual display (xvfb-run), closing
// by itself after a while with a screenshot; and without any display, one clear message; an
// Is-XFEM scene is refused by name.

#include "app/run_command.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>
#include <stb/stb_image.h>

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <sys/wait.h>
#include <memory>

using namespace vox::test;
namespace fs = std::filesystem;

TEST(View, AWindowOnAVirtualDisplayShowsTheObjectAndTheRates)
{
    if (std::system("command -v xvfb-run > /dev/null 2>&1") != 0) GTEST_SKIP() << "xvfb-run is not installed (scripts/install-deps.sh installs it)";
    ScratchDir dir;
    const std::string program = VOX_VOXSCULPT_EXE;
    const std::string scene = quote(std::string(VOX_SOURCE_DIR) + "/data/scenes/wet_push.json");
    const std::string command = "xvfb-run -a -s '-screen 0 1280x1024x24' " + quote(program) + " view " + scene +
                                " --device mouse --size 640x480 --exit-after 3 --screenshot " + quote(dir.path("view.png")) + " > " + quote(dir.path("log.txt")) + " 2>&1";
    ASSERT_EQ(std::system(command.c_str()), 0) << command;
    int w = 0, h = 0, channels = 0;
    std::unique_ptr<unsigned char, void (*)(void*)> data(stbi_load(dir.path("view.png").c_str(), &w, &h, &channels, 3), stbi_image_free);
    ASSERT_TRUE(data);
    EXPECT_EQ(w, 640);
    EXPECT_EQ(h, 480);
    // The block (label 1: Slicer's tissue green) covers a good part of the window; the overlay's
    // dark text is there too.
    int block = 0, text = 0;
    for (int i = 0; i < w * h; ++i) {
        const unsigned char* c = data.get() + 3 * i;
        block += c[1] > c[2] + 20 && c[1] > 100;
        text += c[0] < 40 && c[1] < 40 && c[2] < 40;
    }
    EXPECT_GT(block, w * h / 20);
    EXPECT_GT(text, 100);
}

TEST(View, WithoutADisplayItSaysSoAndExits)
{
    if (std::getenv("DISPLAY") && *std::getenv("DISPLAY")) GTEST_SKIP() << "a display is present";
    const auto r = run_voxsculpt("view " + quote(std::string(VOX_SOURCE_DIR) + "/data/scenes/wet_push.json") + " --exit-after 1");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("no window"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("xvfb-run"), std::string::npos) << r.err;
}

TEST(View, AForceFeedbackDeviceDrivesTheToolThroughItsVendorsLibrary)
{
    // The tests' fake libdhd.so (docs/devices.md): an omega that moves down 2 mm/s from where the
    // tool starts. The viewer opens it, places its frame at the tool, and runs to the end.
    if (std::system("command -v xvfb-run > /dev/null 2>&1") != 0) GTEST_SKIP() << "xvfb-run is not installed (scripts/install-deps.sh installs it)";
    ScratchDir dir;
    const std::string scene = quote(std::string(VOX_SOURCE_DIR) + "/data/scenes/wet_push.json");
    const std::string env = "VOX_LIBDHD=" + quote(VOX_FAKE_VENDOR_DIR "/libdhd.so") + " FAKE_DHD_PATH='0 0 0 0 0 -0.002' ";
    const std::string command = env + "xvfb-run -a -s '-screen 0 1280x1024x24' " + quote(VOX_VOXSCULPT_EXE) + " view " + scene +
                                " --device forcedimension --size 320x240 --exit-after 2 > " + quote(dir.path("log.txt")) + " 2>&1";
    ASSERT_EQ(std::system(command.c_str()), 0) << command;
    std::ifstream in(dir.path("log.txt"));
    const std::string log((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_NE(log.find("is driven by: Force Dimension omega.6 (fake)"), std::string::npos) << log;

    // Without the library: one line naming it, exit 2.
    const std::string missing = "VOX_LIBHD=/nonexistent/libHD.so xvfb-run -a -s '-screen 0 1280x1024x24' " + quote(VOX_VOXSCULPT_EXE) +
                                " view " + scene + " --device openhaptics --exit-after 1 > " + quote(dir.path("missing.txt")) + " 2>&1";
    EXPECT_EQ(WEXITSTATUS(std::system(missing.c_str())), 2);
    std::ifstream m(dir.path("missing.txt"));
    const std::string said((std::istreambuf_iterator<char>(m)), std::istreambuf_iterator<char>());
    EXPECT_NE(said.find("/nonexistent/libHD.so not found (from VOX_LIBHD)"), std::string::npos) << said;
}
