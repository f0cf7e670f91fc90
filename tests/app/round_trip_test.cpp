// Round trips with the tools medical users already have: a 3D Slicer segmentation in, selected
// by segment name, sculpted in a run, and the result out again on the scan's grid, read back by
// nibabel (Debian's python3-nibabel) for the NIfTI label map.

#include "app/run_command.hpp"
#include "test_support.hpp"

#include <Eigen/Core>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <cstring>
#include <iterator>
#include <sstream>

namespace fs = std::filesystem;
using vox::test::fresh_dir;
using vox::test::quote;
using vox::test::run_voxsculpt;

namespace {

std::string head_of(const fs::path& file, std::size_t bytes)
{
    std::ifstream in(file, std::ios::binary);
    std::string text(bytes, '\0');
    in.read(text.data(), static_cast<std::streamsize>(bytes));
    text.resize(static_cast<std::size_t>(in.gcount()));
    return text.substr(0, text.find("\n\n"));
}

} // namespace

TEST(RoundTrip, ASlicerSegmentationSculptedInARunIsWrittenBackOnItsGridWithItsNamesAndColours)
{
    const fs::path d = fresh_dir("round_trip_seg");
    const std::string seg = (d / "liver3.seg.nrrd").string();
    ASSERT_EQ(vox::test::run_python(VOX_SOURCE_DIR "/tests/io/write_segmentation.py", {VOX_SOURCE_DIR "/data/liver.inr.gz", seg}), 0);
    const nlohmann::json counts = nlohmann::json::parse(std::ifstream(seg + ".counts.json"));

    // info lists the three segments with their voxels.
    const auto info = run_voxsculpt("info " + quote(seg));
    ASSERT_EQ(info.exit_code, 0) << info.err;
    EXPECT_NE(info.out.find("tumor, Segment_3, layer 1, value 1, " + counts["tumor"].dump() + " voxels"), std::string::npos) << info.out;

    // A sphere carves into the liver's front for 0.3 s; the back is held.
    std::ofstream(d / "scene.json") << R"({
        "object": {"volume": "liver3.seg.nrrd", "select": {"segment": ["liver", "tumor"]}, "levels": 3},
        "materials": {"default": {"youngs_modulus_pa": 3e4, "poisson_ratio": 0.45, "density_kg_m3": 1060}},
        "solver": {"type": "dbg", "dt_s": 0.01, "preconditioner": "jacobi"},
        "constraints": [{"type": "fixed", "box_mm": [[0, 100, 80], [270, 220, 190]]}],
        "tools": [{"name": "loop", "shape": "sphere", "radius_mm": 6, "action": "cut", "cut_mode": "remove"}],
        "script": [{"t_s": 0.0, "tool": "loop", "position_mm": [120, -10, 120]},
                   {"t_s": 0.3, "tool": "loop", "position_mm": [120, 40, 120]}],
        "output": {"dir": "out", "mesh_every_n_frames": 100, "volumes": ["seg.nrrd", "nii.gz", "vdb"]}})";
    const auto run = run_voxsculpt("run " + quote((d / "scene.json").string()) + " --frames 30");
    ASSERT_EQ(run.exit_code, 0) << run.err;
    for (const char* name : {"final.seg.nrrd", "final.nii.gz", "final.vdb"}) EXPECT_TRUE(fs::exists(d / "out" / name)) << name;

    // The segmentation written back: the input's grid (without its layer axis), the two segments
    // picked with their names, IDs and colours.
    const std::string in = head_of(seg, 8192), back = head_of(d / "out" / "final.seg.nrrd", 8192);
    const auto line = [](const std::string& header, const std::string& key) {
        const std::size_t at = header.find("\n" + key);
        return at == std::string::npos ? std::string("(none)") : header.substr(at + 1, header.find('\n', at + 1) - at - 1);
    };
    EXPECT_EQ(line(back, "sizes:"), "sizes: 219 177 80");
    EXPECT_EQ(line(back, "space:"), "space: left-posterior-superior");
    EXPECT_EQ(line(back, "Segment0_Name"), "Segment0_Name:=liver");
    EXPECT_EQ(line(back, "Segment1_Name"), "Segment1_Name:=tumor");
    EXPECT_EQ(line(back, "Segment1_ID"), "Segment1_ID:=Segment_3");
    EXPECT_EQ(line(back, "Segment1_Color"), "Segment1_Color:=0.56 0.93 0.56");

    // nibabel reads the NIfTI label map: the same grid (RAS: x and y negated), and the carving shows
    // as fewer liver voxels than selected, the tumor untouched.
    const std::string check =
        "import sys, json, numpy as np, nibabel as nib\n"
        "img = nib.load(sys.argv[1])\n"
        "a = np.asarray(img.dataobj)\n"
        "print(json.dumps({'shape': list(a.shape), 'affine': img.affine.tolist(),\n"
        "                  'liver': int((a == 1).sum()), 'tumor': int((a == 2).sum())}))\n";
    std::ofstream(d / "check.py") << check;
    ASSERT_EQ(vox::test::run_python((d / "check.py").string(), {(d / "out" / "final.nii.gz").string()}, (d / "nib.json").string()), 0);
    const nlohmann::json nib = nlohmann::json::parse(std::ifstream(d / "nib.json"));
    EXPECT_EQ(nib["shape"], nlohmann::json({219, 177, 80}));
    EXPECT_NEAR(nib["affine"][0][0].get<double>(), -1.234376, 1e-6);
    EXPECT_NEAR(nib["affine"][1][1].get<double>(), -1.234376, 1e-6);
    EXPECT_NEAR(nib["affine"][2][2].get<double>(), 1.33333, 1e-6);
    EXPECT_NEAR(nib["affine"][2][3].get<double>(), 79.9998, 1e-4);
    EXPECT_EQ(nib["tumor"].get<std::uint64_t>(), counts["tumor"].get<std::uint64_t>());
    EXPECT_LT(nib["liver"].get<std::uint64_t>(), counts["liver_outside_tumor"].get<std::uint64_t>());
    EXPECT_GT(nib["liver"].get<std::uint64_t>(), counts["liver_outside_tumor"].get<std::uint64_t>() - 20000);
}

TEST(RoundTrip, TheFiniteElementMeshOfARunReadsInMeshioAndABarStretchedByAKnownForceShowsFOverA)
{
    // A 40 x 10 x 10 mm bar (1 mm voxels, 2 mm elements) held at x = 0 and pulled along x by 1 N
    // at its far end, solved to equilibrium: away from its ends the stress is uniaxial, F / A =
    // 1 N / 100 mm^2 = 10 kPa, and so is its von Mises stress.
    const fs::path d = fresh_dir("round_trip_vtu");
    std::ofstream(d / "bar.json") << R"({
        "object": {"phantom": {"shape": "beam", "size_mm": [40, 10, 10], "voxel_mm": 1}, "levels": 1},
        "materials": {"default": {"youngs_modulus_pa": 1e6, "poisson_ratio": 0.3, "density_kg_m3": 1000}},
        "solver": {"type": "dbg", "mode": "static", "cg_tolerance": 1e-10},
        "gravity_m_s2": [0, 0, 0],
        "constraints": [{"type": "fixed", "box_mm": [[-1, -1, -1], [0.6, 11, 11]]}],
        "loads": [{"box_mm": [[38.6, -1, -1], [41, 11, 11]], "force_n": [1, 0, 0]}],
        "output": {"dir": "out", "vtu_every_n_frames": 1}})";
    const auto run = run_voxsculpt("run " + quote((d / "bar.json").string()) + " --frames 2");
    ASSERT_EQ(run.exit_code, 0) << run.err;
    ASSERT_TRUE(fs::exists(d / "out" / "mesh.pvd"));

    const std::string read =
        "import sys, json, numpy as np, meshio\n"
        "m = meshio.read(sys.argv[1])\n"
        "c = m.cells[0]\n"
        "centre = m.points[c.data].mean(axis=1)\n"
        "vm = m.cell_data['von_mises_pa'][0]\n"
        "mid = (centre[:, 0] > 14) & (centre[:, 0] < 26)\n"
        "print(json.dumps({'type': c.type, 'cells': len(c.data), 'points': len(m.points),\n"
        "    'fields': sorted(m.cell_data.keys()), 'point_fields': sorted(m.point_data.keys()),\n"
        "    'mid_min': float(vm[mid].min()), 'mid_max': float(vm[mid].max()),\n"
        "    'stretch_10_30': float(np.mean(m.point_data['displacement_mm'][np.abs(m.points[:, 0] - 29.5 - m.point_data['displacement_mm'][:, 0]) < 0.01, 0])\n"
        "                       - np.mean(m.point_data['displacement_mm'][np.abs(m.points[:, 0] - 9.5 - m.point_data['displacement_mm'][:, 0]) < 0.01, 0]))}))\n";
    std::ofstream(d / "read.py") << read;
    ASSERT_EQ(vox::test::run_python((d / "read.py").string(), {(d / "out" / "mesh_00002.vtu").string()}, (d / "vtu.json").string()), 0);
    const nlohmann::json m = nlohmann::json::parse(std::ifstream(d / "vtu.json"));
    EXPECT_EQ(m["type"], "hexahedron");
    EXPECT_EQ(m["cells"], 20 * 5 * 5);
    for (const char* field : {"dominant_label", "level", "piece", "plastic_strain", "von_mises_pa", "water", "fraction_label_1"})
        EXPECT_NE(std::find(m["fields"].begin(), m["fields"].end(), field), m["fields"].end()) << field;
    EXPECT_EQ(m["point_fields"], nlohmann::json({"displacement_mm", "velocity_mm_s"}));
    EXPECT_NEAR(m["mid_min"].get<double>(), 1e4, 0.02 * 1e4);
    EXPECT_NEAR(m["mid_max"].get<double>(), 1e4, 0.02 * 1e4);
    // Between the node planes at x = 9.5 and 29.5 mm (at rest) the bar stretches by F L / (E A) =
    // 1 * 0.02 / (1e6 * 1e-4) m = 0.2 mm.
    EXPECT_NEAR(m["stretch_10_30"].get<double>(), 0.2, 0.01);
}

namespace {

/// The Khronos glTF validator from the npm registry (tests/tools/gltf, its version locked),
/// installed once into the temporary folder; the command that runs it on a file.
std::string gltf_validator()
{
    const fs::path dir = fs::temp_directory_path() / "voxsculpt-gltf-validator";
    const fs::path source = VOX_SOURCE_DIR "/tests/tools/gltf";
    fs::create_directories(dir);
    for (const char* file : {"package.json", "package-lock.json", "validate.mjs"})
        fs::copy_file(source / file, dir / file, fs::copy_options::overwrite_existing);
    if (!fs::exists(dir / "node_modules" / "gltf-validator")) {
        const std::string install = "cd " + quote(dir.string()) + " && npm ci --no-audit --no-fund --silent > /dev/null 2>&1";
        EXPECT_EQ(std::system(install.c_str()), 0) << install << " (needs node and npm, and the npm registry)";
    }
    return "node " + quote((dir / "validate.mjs").string());
}

} // namespace

TEST(RoundTrip, TheLiverIncisionWritesAValidGlbInMetresWithGltfsAxesAndItsMeshForParaView)
{
    // The bundled incision for 40 frames: final.glb is checked by the Khronos validator, and its
    // bounds against the surface's own (final.obj) under +X = x, +Y = z, +Z = -y, metres; the
    // finite-element mesh every 20 frames is read by meshio through mesh.pvd.
    const fs::path d = fresh_dir("round_trip_glb");
    std::ifstream in(VOX_SOURCE_DIR "/data/scenes/liver_incision.json");
    std::string scene{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    const std::string volume = "\"../liver.inr.gz\"";
    scene.replace(scene.find(volume), volume.size(), "\"" VOX_SOURCE_DIR "/data/liver.inr.gz\"");
    const std::string output = "\"mesh_every_n_frames\": 25}";
    scene.replace(scene.find(output), output.size(), "\"mesh_every_n_frames\": 25, \"vtu_every_n_frames\": 20}");
    std::ofstream(d / "incision.json") << scene;
    const auto run = run_voxsculpt("run " + quote((d / "incision.json").string()) + " --frames 40 --out " + quote((d / "out").string()));
    ASSERT_EQ(run.exit_code, 0) << run.err;

    const std::string command = gltf_validator() + " " + quote((d / "out" / "final.glb").string()) + " > " + quote((d / "report.json").string());
    const int validated = std::system(command.c_str());
    const nlohmann::json report = nlohmann::json::parse(std::ifstream(d / "report.json"));
    EXPECT_EQ(validated, 0) << report.dump(1);
    EXPECT_EQ(report["errors"], 0) << report.dump(1);
    EXPECT_EQ(report["warnings"], 0) << report.dump(1);

    // The POSITION accessor's bounds against final.obj's vertices (mm, LPS).
    std::ifstream glb(d / "out" / "final.glb", std::ios::binary);
    const std::string bytes{std::istreambuf_iterator<char>(glb), std::istreambuf_iterator<char>()};
    std::uint32_t json_length = 0;
    std::memcpy(&json_length, bytes.data() + 12, 4);
    const nlohmann::json gltf = nlohmann::json::parse(bytes.substr(20, json_length));
    const nlohmann::json& position = gltf["accessors"][0];
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
    std::ifstream obj(d / "out" / "final.obj");
    for (std::string line; std::getline(obj, line);)
        if (line.rfind("v ", 0) == 0) {
            std::istringstream s(line.substr(2));
            Eigen::Vector3d p;
            s >> p.x() >> p.y() >> p.z();
            lo = lo.cwiseMin(p);
            hi = hi.cwiseMax(p);
        }
    EXPECT_NEAR(position["min"][0].get<double>(), 1e-3 * lo.x(), 1e-6);
    EXPECT_NEAR(position["max"][1].get<double>(), 1e-3 * hi.z(), 1e-6);
    EXPECT_NEAR(position["min"][2].get<double>(), -1e-3 * hi.y(), 1e-6);
    EXPECT_NEAR(position["max"][2].get<double>(), -1e-3 * lo.y(), 1e-6);
    EXPECT_EQ(gltf["materials"][0]["name"], "label 255");

    // Every mesh mesh.pvd lists, read by meshio: the liver's level-4 hexahedra with all fields.
    const std::string read =
        "import sys, os, json, re, meshio\n"
        "folder = os.path.dirname(sys.argv[1])\n"
        "files = re.findall(r'file=\"([^\"]+)\"', open(sys.argv[1]).read())\n"
        "out = []\n"
        "for f in files:\n"
        "    m = meshio.read(os.path.join(folder, f))\n"
        "    out.append({'file': f, 'type': m.cells[0].type, 'cells': len(m.cells[0].data), 'fields': len(m.cell_data),\n"
        "                'max_von_mises': float(m.cell_data['von_mises_pa'][0].max())})\n"
        "print(json.dumps(out))\n";
    std::ofstream(d / "read.py") << read;
    ASSERT_EQ(vox::test::run_python((d / "read.py").string(), {(d / "out" / "mesh.pvd").string()}, (d / "vtu.json").string()), 0);
    const nlohmann::json meshes = nlohmann::json::parse(std::ifstream(d / "vtu.json"));
    ASSERT_EQ(meshes.size(), 3u); // frames 0, 20 and 40
    for (const nlohmann::json& m : meshes) {
        EXPECT_EQ(m["type"], "hexahedron");
        EXPECT_GT(m["cells"].get<int>(), 1200);
        EXPECT_EQ(m["fields"], 7); // level, piece, dominant label, fraction of label 255, plastic strain, water, von Mises
    }
    EXPECT_LT(meshes[0]["max_von_mises"].get<double>(), 1e-6); // at rest: rounding only
    EXPECT_GT(meshes[2]["max_von_mises"].get<double>(), 0.0);
}

TEST(RoundTrip, IsXfemsMeshShowsTheCrackAsSubTetrahedraThatPartitionEachCutTetrahedron)
{
    // The bundled Is-XFEM bar cut through: after the cut the mesh is two pieces, the cut
    // tetrahedra written as their sides' sub-tetrahedra; at rest those fill each cut tetrahedron
    // exactly, so the mesh's rest volume is the uncut one's.
    const fs::path d = fresh_dir("round_trip_vtu_isxfem");
    std::ifstream in(VOX_SOURCE_DIR "/data/scenes/bar_cut_isxfem.json");
    std::string scene{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    const std::string output = "\"mesh_every_n_frames\": 10}";
    scene.replace(scene.find(output), output.size(), "\"mesh_every_n_frames\": 100, \"vtu_every_n_frames\": 30}");
    std::ofstream(d / "bar.json") << scene;
    const auto run = run_voxsculpt("run " + quote((d / "bar.json").string()) + " --frames 30 --out " + quote((d / "out").string()));
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const std::string read =
        "import sys, json, numpy as np, meshio\n"
        "out = {}\n"
        "for name in ('mesh_00000.vtu', 'mesh_00030.vtu'):\n"
        "    m = meshio.read(sys.argv[1] + '/' + name)\n"
        "    c = m.cells[0].data\n"
        "    rest = m.points - m.point_data['displacement_mm']\n"
        "    e = rest[c[:, 1:]] - rest[c[:, :1]]\n"
        "    out[name] = {'type': m.cells[0].type, 'cells': len(c), 'rest_volume': float(np.abs(np.linalg.det(e)).sum() / 6),\n"
        "                 'pieces': len(set(m.cell_data['piece'][0])), 'cut_cells': int((m.cell_data['region'][0] >= 0).sum())}\n"
        "print(json.dumps(out))\n";
    std::ofstream(d / "read.py") << read;
    ASSERT_EQ(vox::test::run_python((d / "read.py").string(), {(d / "out").string()}, (d / "vtu.json").string()), 0);
    const nlohmann::json m = nlohmann::json::parse(std::ifstream(d / "vtu.json"));
    const nlohmann::json &before = m["mesh_00000.vtu"], &after = m["mesh_00030.vtu"];
    EXPECT_EQ(before["type"], "tetra");
    EXPECT_EQ(before["pieces"], 1);
    EXPECT_EQ(before["cut_cells"], 0);
    EXPECT_EQ(after["pieces"], 2);
    EXPECT_GT(after["cut_cells"].get<int>(), 0);
    EXPECT_NEAR(after["rest_volume"].get<double>(), before["rest_volume"].get<double>(), 1e-6 * before["rest_volume"].get<double>());
}
