// Session journals: a device run killed mid-stroke resumes from its journal with the same cuts as
// an uninterrupted run had after that stroke (the voxels and opened faces of the branched grid,
// the cracks of Is-XFEM), compared on each method's own state; journals from another scene or
// program version, or damaged, are refused; undos in a journal drop the cuts they undid.

#include "core/version.hpp"
#include "io/scene.hpp"
#include "io/scene_object.hpp"
#include "sim/dbg_method.hpp"
#include "sim/device_run.hpp"
#include "sim/frame_loop.hpp"
#include "sim/isxfem_method.hpp"
#include "sim/journal.hpp"
#include "sim/method_factory.hpp"

#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <set>
#include <thread>
#include <tuple>

extern char** environ;

namespace vox::sim {
namespace {

namespace fs = std::filesystem;

fs::path fresh_dir(const std::string& name)
{
    const fs::path d = fs::temp_directory_path() / ("voxsculpt-journal-" + std::to_string(::getpid()) + "-" + name);
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

/// A bar held at one end; the blade cuts halfway down at x = 70 and leaves, then cuts through at
/// x = 40 and rests there: two strokes, then a long still second (time for a kill mid-run).
fs::path write_scene(const fs::path& dir, const std::string& solver)
{
    const fs::path path = dir / "scene.json";
    std::ofstream(path) << R"({
        "object": {"phantom": {"shape": "beam", "size_mm": [100, 10, 10], "voxel_mm": 1.0}, "levels": 2},
        "materials": {"default": {"youngs_modulus_pa": 1e5, "poisson_ratio": 0.3, "density_kg_m3": 1000}},
        "solver": {"type": ")" << solver << R"(", "dt_s": 0.01, "cg_tolerance": 1e-6},
        "gravity_m_s2": [0, 0, -9.81],
        "constraints": [{"type": "fixed", "box_mm": [[-1, -1, -1], [2, 11, 11]]}],
        "tools": [{"name": "blade", "shape": "blade", "size_mm": [40, 1, 20]}],
        "script": [
            {"t_s": 0.0, "tool": "blade", "position_mm": [70.3, 5, 20.5], "orientation_wxyz": [0.7071068, 0, 0, 0.7071068]},
            {"t_s": 0.04, "tool": "blade", "position_mm": [70.3, 5, 5], "orientation_wxyz": [0.7071068, 0, 0, 0.7071068]},
            {"t_s": 0.1, "tool": "blade", "position_mm": [70.3, 5, 40], "orientation_wxyz": [0.7071068, 0, 0, 0.7071068]},
            {"t_s": 0.2, "tool": "blade", "position_mm": [40.3, 5, 20.5], "orientation_wxyz": [0.7071068, 0, 0, 0.7071068]},
            {"t_s": 0.26, "tool": "blade", "position_mm": [40.3, 5, -15], "orientation_wxyz": [0.7071068, 0, 0, 0.7071068]},
            {"t_s": 1.5, "tool": "blade", "position_mm": [40.3, 5, -15], "orientation_wxyz": [0.7071068, 0, 0, 0.7071068]}
        ]
    })";
    return path;
}

/// What a method's cuts made of its object, read from its own state (not from its cut record).
struct CutState {
    std::set<std::tuple<int, int, int>> alive;      ///< dbg: voxels left
    std::set<std::tuple<int, int, int, int>> opened; ///< dbg: faces opened (voxel, axis)
    std::vector<std::vector<double>> element_cuts;   ///< Is-XFEM: per tetrahedron, each cut's id and level values
    std::size_t surface_triangles = 0;
    std::size_t pieces = 0;
    bool operator==(const CutState&) const = default;
};

CutState cut_state(const Method& method)
{
    CutState s;
    if (const auto* dbg = dynamic_cast<const DbgMethod*>(&method)) {
        const grid::FineVoxels& voxels = dbg->grid().voxels();
        for (std::uint32_t v = 0; v < voxels.slots(); ++v) {
            if (!voxels.alive(v)) continue;
            const grid::Coord c = voxels.coord(v);
            s.alive.insert({c.x(), c.y(), c.z()});
            for (int axis = 0; axis < 3; ++axis)
                if (voxels.face_disconnected(v, axis)) s.opened.insert({c.x(), c.y(), c.z(), axis});
        }
    } else {
        const auto& xfem = dynamic_cast<const IsxfemMethod&>(method);
        for (const isxfem::XfemElement& e : xfem.simulation().model().elements()) {
            std::vector<double> cuts;
            for (const isxfem::ElementCut& c : e.cuts) {
                cuts.push_back(c.id);
                cuts.insert(cuts.end(), c.phi.begin(), c.phi.end());
            }
            s.element_cuts.push_back(std::move(cuts));
        }
    }
    s.surface_triangles = method.surface_mesh().triangles.size();
    s.pieces = method.piece_count();
    return s;
}

/// Runs `voxsculpt ARGS...` and kills it (SIGKILL) once `journal` holds a stroke line. True when
/// it was killed, false when it ended first.
bool run_and_kill(const std::vector<std::string>& args, const fs::path& journal)
{
    std::vector<char*> argv;
    std::string exe = VOX_VOXSCULPT_EXE;
    argv.push_back(exe.data());
    std::vector<std::string> copy = args;
    for (std::string& a : copy) argv.push_back(a.data());
    argv.push_back(nullptr);
    pid_t pid = 0;
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
    const int spawned = posix_spawn(&pid, exe.c_str(), &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (spawned != 0) return false;
    int status = 0;
    for (;;) {
        if (waitpid(pid, &status, WNOHANG) == pid) return false; // it ended by itself
        std::ifstream in(journal);
        std::string header, stroke;
        if (std::getline(in, header) && std::getline(in, stroke) && in) break; // a complete stroke line
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    kill(pid, SIGKILL);
    waitpid(pid, &status, 0);
    return WIFSIGNALED(status);
}

class JournalOnEachMethod : public ::testing::TestWithParam<io::SolverType> {};

TEST_P(JournalOnEachMethod, AKilledDeviceRunResumesWithTheCutsOfAnUninterruptedRunAtThatStroke)
{
    const std::string method_name(io::solver_type_name(GetParam()));
    const fs::path dir = fresh_dir(method_name);
    const fs::path scene_file = write_scene(dir, method_name);
    const io::Scene scene = io::load_scene(scene_file);
    const auto labels = std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene));

    // The uninterrupted run, as `voxsculpt run --device script` makes it, the state kept at each
    // stroke's end.
    std::vector<CutState> after_stroke;
    std::vector<std::vector<double>> motion_after_stroke;
    {
        auto method = open_method(scene, labels).method;
        ToolPolicy tools(scene);
        DeviceRun device(scene, tools, DeviceOptions{});
        FrameLoop loop(scene, *method, tools, &device);
        JournalWriter writer(dir / "reference.journal", journal_header(scene_file, *method), *method);
        StrokeEnds ends;
        for (int f = 0; f < 150; ++f) {
            const FrameStats frame = loop.next();
            const int before = writer.strokes();
            if (ends.after_frame(frame)) writer.end_stroke(*method, frame.frame, frame.t_s);
            if (writer.strokes() > before) {
                after_stroke.push_back(cut_state(*method));
                motion_after_stroke.push_back(method->motion());
            }
        }
    }
    ASSERT_GE(after_stroke.size(), 2u) << "the blade made two strokes";

    // The same run in the program, killed once its journal holds a stroke.
    const fs::path out = dir / "run";
    const fs::path journal = journal_path(out);
    ASSERT_TRUE(run_and_kill({"run", scene_file.string(), "--device", "script", "--frames", "150", "--out", out.string()}, journal))
        << "the run ended before it was killed";
    EXPECT_FALSE(fs::exists(out)) << "a killed run has no output folder";

    // Resumed: the object cut as the uninterrupted run had it after the journal's last stroke.
    auto resumed = open_method(scene, labels).method;
    const Journal read = read_journal(journal, journal_header(scene_file, *resumed));
    ASSERT_GE(read.strokes.size(), 1u);
    ASSERT_LT(read.strokes.size(), after_stroke.size()) << "killed before its last stroke";
    resume(*resumed, read);
    const CutState now = cut_state(*resumed);
    const CutState& expected = after_stroke[read.strokes.size() - 1];
    EXPECT_GT(resumed->cut_count(), 0u);
    EXPECT_EQ(now.alive, expected.alive);
    EXPECT_EQ(now.opened, expected.opened);
    EXPECT_EQ(now.element_cuts, expected.element_cuts);
    EXPECT_EQ(now.surface_triangles, expected.surface_triangles);
    EXPECT_EQ(now.pieces, expected.pieces);
    // And it moves as it did then (JOURNAL.state): positions, velocities, water, plastic strain.
    EXPECT_EQ(resumed->motion(), motion_after_stroke[read.strokes.size() - 1]);

    // The program resumes it too and goes on cutting; its own journal starts with the cuts resumed,
    // so it can be resumed in turn. (The tools start afresh, so what follows is a new stroke, not
    // the killed run's to the bit.)
    const fs::path again = dir / "again";
    const std::string command = std::string(VOX_VOXSCULPT_EXE) + " -q run " + scene_file.string() + " --device script --frames 150 --resume " +
                                journal.string() + " --out " + again.string();
    ASSERT_EQ(std::system(command.c_str()), 0) << command;
    EXPECT_TRUE(fs::exists(again / "stats.json"));
    const Journal continued = read_journal(journal_path(again), journal_header(scene_file, *resumed));
    ASSERT_GE(continued.strokes.size(), 2u);
    EXPECT_EQ(continued.strokes.front().cuts, read.cuts());
    EXPECT_EQ(continued.strokes.front().frame, read.strokes.back().frame);
    EXPECT_GT(continued.cuts().size(), read.cuts().size());
}

INSTANTIATE_TEST_SUITE_P(Methods, JournalOnEachMethod, ::testing::Values(io::SolverType::dbg, io::SolverType::isxfem, io::SolverType::shape_matching),
                         [](const auto& method) { return std::string(io::solver_type_name(method.param)); });

/// A journal file: the header for `header`, then `lines`.
fs::path write_journal(const fs::path& dir, const JournalHeader& header, const std::string& lines)
{
    const fs::path path = dir / "j.journal";
    std::ofstream(path) << nlohmann::json{{"journal", "voxsculpt session journal"}, {"format", 1},        {"program", header.program},
                                          {"scene", header.scene},                   {"scene_fnv1a", header.scene_hash},
                                          {"method", header.method},                 {"level", header.level}}
                                   .dump()
                        << '\n'
                        << lines;
    return path;
}

std::string refusal(const fs::path& path, const JournalHeader& expected)
{
    try {
        (void)read_journal(path, expected);
    } catch (const InputError& e) {
        return e.what();
    }
    return "(accepted)";
}

TEST(Journal, AnotherProgramSceneOrMethodIsRefusedNamingTheFile)
{
    const fs::path dir = fresh_dir("refused");
    const JournalHeader ours{program_version(), "scene.json", "00000000000000aa", "dbg", 2};
    JournalHeader other = ours;
    other.program = "voxsculpt 0.0.1";
    const fs::path p1 = write_journal(dir, other, "");
    EXPECT_EQ(refusal(p1, ours), p1.string() + ": written by voxsculpt 0.0.1, this is " + program_version() +
                                     ": a journal is resumed by the program version that wrote it");
    other = ours;
    other.scene_hash = "00000000000000bb";
    EXPECT_NE(refusal(write_journal(dir, other, ""), ours).find("written for another scene"), std::string::npos);
    other = ours;
    other.method = "isxfem";
    EXPECT_NE(refusal(write_journal(dir, other, ""), ours).find("written for the isxfem method at level 2; this simulates dbg"),
              std::string::npos);
    std::ofstream(dir / "not.journal") << "{\"object\": {}}\n";
    EXPECT_NE(refusal(dir / "not.journal", ours).find("not a VoxSculpt session journal"), std::string::npos);
}

TEST(Journal, ATornLastLineIsLeftOutAndUndosDropTheCutsTheyUndid)
{
    const fs::path dir = fresh_dir("lines");
    const JournalHeader h{program_version(), "scene.json", "00000000000000aa", "dbg", 2};
    // Stroke 1 makes cuts A and B; stroke 2 follows an undo of B and makes C; stroke 3 was being
    // written when the process died.
    const fs::path path = write_journal(dir, h,
                                        R"({"stroke": 1, "frame": 10, "t_s": 0.1, "cuts_before": 0, "cuts": ["A", "B"]})"
                                        "\n"
                                        R"({"stroke": 2, "frame": 20, "t_s": 0.2, "cuts_before": 1, "cuts": ["C"]})"
                                        "\n"
                                        R"({"stroke": 3, "frame": 30, "t_s": 0.3, "cuts_bef)");
    const Journal j = read_journal(path, h);
    EXPECT_TRUE(j.torn_tail);
    ASSERT_EQ(j.strokes.size(), 2u);
    EXPECT_EQ(j.strokes.back().frame, 20);
    EXPECT_EQ(j.cuts(), nlohmann::json({"A", "C"}));
    // A stroke that begins after more cuts than were made is a damaged journal.
    const fs::path gap = write_journal(dir, h, R"({"stroke": 1, "frame": 10, "t_s": 0.1, "cuts_before": 3, "cuts": []})"
                                               "\n");
    EXPECT_NE(refusal(gap, h).find("stroke 1 begins after cut 3, but the strokes before it made 0"), std::string::npos);
}

TEST(Journal, CutsThatDoNotFitTheObjectAreRefused)
{
    const fs::path dir = fresh_dir("misfit");
    const fs::path scene_file = write_scene(dir, "dbg");
    const io::Scene scene = io::load_scene(scene_file);
    auto method = open_method(scene, std::make_shared<const grid::LabelGrid>(io::load_scene_object(scene))).method;
    const JournalHeader h = journal_header(scene_file, *method);
    const fs::path path = write_journal(dir, h, R"({"stroke": 1, "frame": 1, "t_s": 0.01, "cuts_before": 0, "cuts": [{"removed": [[500, 0, 0]], "faces": []}]})"
                                                "\n");
    try {
        resume(*method, read_journal(path, h));
        FAIL() << "resumed";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("cut 0: removes voxel (500, 0, 0), which the object does not have"), std::string::npos) << e.what();
    }
    EXPECT_EQ(method->cut_count(), 0u);
}

} // namespace
} // namespace vox::sim
