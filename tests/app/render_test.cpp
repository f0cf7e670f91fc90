// Pictures without a display: the sphere phantom rendered orthographically covers the share of
// the frame a disk framed with the renderer's margin covers, and its outline is round; the cut
// cylinder shows two separate silhouettes; bad picture options get one clear message.

#include "app/run_command.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>
#include <stb/stb_image.h>

#include <cmath>
#include <memory>
#include <vector>

using namespace vox::test;
namespace fs = std::filesystem;

namespace {

struct Picture {
    int width = 0, height = 0;
    std::vector<unsigned char> rgb;
    [[nodiscard]] const unsigned char* at(int x, int y) const { return rgb.data() + 3 * (static_cast<std::size_t>(y) * width + x); }
};

Picture read_png(const fs::path& path)
{
    Picture p;
    int channels = 0;
    std::unique_ptr<unsigned char, void (*)(void*)> data(stbi_load(path.c_str(), &p.width, &p.height, &channels, 3), stbi_image_free);
    EXPECT_TRUE(data) << path;
    if (data) p.rgb.assign(data.get(), data.get() + 3 * p.width * p.height);
    return p;
}

/// Pixels unlike the plain background (236, 238, 242).
bool foreground(const unsigned char* c) { return std::abs(c[0] - 236) + std::abs(c[1] - 238) + std::abs(c[2] - 242) > 24; }
/// Pixels of the object (its warm material colour), not of the grey-blue tool.
bool object(const unsigned char* c) { return foreground(c) && c[0] > c[2] + 30; }

/// Sizes of the 4-connected components of the pixels `inside` picks, largest first.
template <class Inside>
std::vector<int> components(const Picture& p, Inside inside)
{
    std::vector<int> label(static_cast<std::size_t>(p.width * p.height), -1), sizes, stack;
    for (int start = 0; start < p.width * p.height; ++start) {
        if (label[static_cast<std::size_t>(start)] >= 0 || !inside(p.at(start % p.width, start / p.width))) continue;
        const int id = static_cast<int>(sizes.size());
        sizes.push_back(0);
        stack.push_back(start);
        label[static_cast<std::size_t>(start)] = id;
        while (!stack.empty()) {
            const int i = stack.back();
            stack.pop_back();
            ++sizes.back();
            const int x = i % p.width, y = i / p.width;
            for (const auto& [dx, dy] : {std::pair{1, 0}, std::pair{-1, 0}, std::pair{0, 1}, std::pair{0, -1}}) {
                const int nx = x + dx, ny = y + dy;
                if (nx < 0 || ny < 0 || nx >= p.width || ny >= p.height) continue;
                const int j = ny * p.width + nx;
                if (label[static_cast<std::size_t>(j)] >= 0 || !inside(p.at(nx, ny))) continue;
                label[static_cast<std::size_t>(j)] = id;
                stack.push_back(j);
            }
        }
    }
    std::sort(sizes.rbegin(), sizes.rend());
    return sizes;
}

} // namespace

TEST(Render, TheSpherePhantomCoversTheShareOfTheFrameADiskDoes)
{
    ScratchDir dir;
    ASSERT_EQ(run_voxsculpt("phantom sphere --radius-mm 12 --voxel-mm 0.5 -o " + quote(dir.path("sphere.vdb"))).exit_code, 0);
    const auto r = run_voxsculpt("render " + quote(dir.path("sphere.vdb")) + " --camera front,ortho --size 300x300 --smooth 0 --out " +
                                 quote(dir.path("sphere.png")));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const Picture p = read_png(dir.path("sphere.png"));
    ASSERT_EQ(p.width, 300);
    ASSERT_EQ(p.height, 300);
    int covered = 0, x_lo = p.width, x_hi = -1, y_lo = p.height, y_hi = -1;
    for (int y = 0; y < p.height; ++y)
        for (int x = 0; x < p.width; ++x)
            if (foreground(p.at(x, y))) {
                ++covered;
                x_lo = std::min(x_lo, x), x_hi = std::max(x_hi, x), y_lo = std::min(y_lo, y), y_hi = std::max(y_hi, y);
            }
    // Framed with 10 % of margin on each side of its widest extent, a disk covers pi / (4 1.1^2)
    // of a square frame (0.649), centred; and it fills pi / 4 of its own bounding square.
    const double share = static_cast<double>(covered) / (p.width * p.height);
    EXPECT_NEAR(share, M_PI / (4.0 * 1.1 * 1.1), 0.02);
    const double w = x_hi - x_lo + 1, h = y_hi - y_lo + 1;
    EXPECT_NEAR(w / h, 1.0, 0.02);
    EXPECT_NEAR(covered / (w * h), M_PI / 4.0, 0.02);
    EXPECT_NEAR(0.5 * (x_lo + x_hi), 149.5, 2.0);
    EXPECT_NEAR(0.5 * (y_lo + y_hi), 149.5, 2.0);
}

TEST(Render, TheCutCylinderShowsTwoSilhouettes)
{
    // The hanging cylinder cut through, 0.12 s later: the lower piece has dropped away from the
    // upper one. Before the cut (the scene at rest) there is one.
    ScratchDir dir;
    const std::string scene = quote(std::string(VOX_SOURCE_DIR) + "/data/scenes/cylinder_cut.json");
    auto r = run_voxsculpt("render " + scene + " --camera front --size 480x360 --out " + quote(dir.path("before.png")));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    r = run_voxsculpt("run " + scene + " --frames 24 --render-every 24 --camera front --size 480x360 --out " + quote(dir.path("run")));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    ASSERT_TRUE(fs::exists(dir.root() / "run" / "frame_00024.png"));
    auto pieces = [](const Picture& p) {
        int n = 0;
        for (int size : components(p, object)) n += size >= 100; // specks of antialiasing aside
        return n;
    };
    EXPECT_EQ(pieces(read_png(dir.path("before.png"))), 1);
    EXPECT_EQ(pieces(read_png(dir.root() / "run" / "final.png")), 2);
}

TEST(Render, BadPictureOptionsNameTheOptionAndTheProblem)
{
    ScratchDir dir;
    const std::string scene = quote(std::string(VOX_SOURCE_DIR) + "/data/scenes/cylinder_cut.json");
    const std::string out = " --out " + quote(dir.path("x.png"));
    for (const auto& [args, expected] : {std::pair{" --camera sideways", "--camera \"sideways\""}, std::pair{" --camera 10,95", "--camera \"10,95\""},
                                         std::pair{" --size 0x100", "--size \"0x100\""}, std::pair{" --size 640", "--size \"640\""}}) {
        const auto r = run_voxsculpt("render " + scene + args + out);
        EXPECT_EQ(r.exit_code, 2) << args;
        EXPECT_NE(r.err.find(expected), std::string::npos) << r.err;
        EXPECT_FALSE(fs::exists(dir.path("x.png")));
    }
    const auto r = run_voxsculpt("render " + scene + " --out " + quote(dir.path("x.jpg")));
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("x.jpg: the picture must be a .png file"), std::string::npos) << r.err;
}
