// OBJ and PLY reader, through OpenMesh: these formats have many variants (OBJ's "v/vt/vn" corners,
// PLY's ascii and binary encodings and property lists), better left to a library. OpenMesh's console
// diagnostics are folded into our one-line errors, and the vertex copies it makes at non-manifold
// faces are welded back so the connectivity is the file's.

#include "core/error.hpp"
#include "core/log.hpp"
#include "io/mesh_readers.hpp"

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/PolyMesh_ArrayKernelT.hh>

#include <array>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <mutex>
#include <sstream>
#include <system_error>

namespace vox::io::detail {
namespace {

struct OpenMeshTraits : OpenMesh::DefaultTraits {
    using Point = OpenMesh::Vec3d;
};
using PolyMesh = OpenMesh::PolyMesh_ArrayKernelT<OpenMeshTraits>;

/// OpenMesh reports problems on its global streams omerr, omlog and omout, by default the
/// console. While alive, this collects omerr in a string (to fold it into one error message) and
/// keeps the console quiet. The streams are global, so readers holding it are serialised.
class OpenMeshMessages {
public:
    OpenMeshMessages() : m_lock(mutex())
    {
        static std::once_flag once;
        std::call_once(once, [] {
            for (OpenMesh::mostream* s : {&omerr(), &omlog(), &omout()}) {
                s->disconnect(std::cerr);
                s->disconnect(std::clog);
                s->disconnect(std::cout);
            }
            omlog().disable();
            omout().disable();
        });
        omerr().connect(m_text);
    }
    ~OpenMeshMessages() { omerr().disconnect(m_text); }
    OpenMeshMessages(const OpenMeshMessages&) = delete;
    OpenMeshMessages& operator=(const OpenMeshMessages&) = delete;

    [[nodiscard]] std::string text()
    {
        omerr().flush();
        return m_text.str();
    }

private:
    static std::mutex& mutex()
    {
        static std::mutex m;
        return m;
    }
    std::unique_lock<std::mutex> m_lock;
    std::ostringstream m_text;
};

std::size_t count_occurrences(const std::string& text, std::string_view what)
{
    std::size_t n = 0;
    for (std::size_t pos = text.find(what); pos != std::string::npos; pos = text.find(what, pos + what.size())) ++n;
    return n;
}

std::string first_line(const std::string& text)
{
    const std::string line = text.substr(0, text.find('\n'));
    return line.empty() ? std::string() : " (OpenMesh: " + line + ")";
}

/// OpenMesh gives each face it cannot attach manifoldly (a complex edge or vertex, e.g. a flipped
/// triangle or a fourth triangle on an edge) fresh copies of its vertices, flagged
/// fixed_nonmanifold. Maps every OpenMesh vertex to an index in `vertices`, copies to the original
/// at the same position, so the connectivity is the file's.
std::vector<int> weld_nonmanifold_copies(const PolyMesh& pm, std::vector<Eigen::Vector3d>& vertices)
{
    std::map<std::array<double, 3>, int> originals;
    std::vector<int> index(pm.n_vertices(), -1);
    std::size_t copies = 0;
    for (const auto v : pm.vertices()) {
        if (pm.status(v).fixed_nonmanifold()) continue;
        const auto& p = pm.point(v);
        index[static_cast<std::size_t>(v.idx())] = static_cast<int>(vertices.size());
        originals.try_emplace({p[0], p[1], p[2]}, static_cast<int>(vertices.size()));
        vertices.emplace_back(p[0], p[1], p[2]);
    }
    for (const auto v : pm.vertices()) {
        if (!pm.status(v).fixed_nonmanifold()) continue;
        const auto& p = pm.point(v);
        const auto it = originals.find({p[0], p[1], p[2]});
        if (it != originals.end()) {
            index[static_cast<std::size_t>(v.idx())] = it->second;
            ++copies;
        } else {
            index[static_cast<std::size_t>(v.idx())] = static_cast<int>(vertices.size());
            vertices.emplace_back(p[0], p[1], p[2]);
        }
    }
    if (copies > 0) log::debug("welded {} vertex copies OpenMesh made at non-manifold faces", copies);
    return index;
}

void check_file_readable(const std::string& path)
{
    std::error_code ec;
    const auto status = std::filesystem::status(path, ec);
    if (ec || !std::filesystem::exists(status)) throw file_error(path, "no such file");
    if (std::filesystem::is_directory(status)) throw file_error(path, "is a folder, not a file");
    if (!std::ifstream(path, std::ios::binary)) throw file_error(path, "cannot open: permission denied or unreadable");
}

} // namespace

TriangleMesh read_with_openmesh(const std::string& path, const std::string& format)
{
    check_file_readable(path);
    PolyMesh pm;
    pm.request_vertex_status(); // lets OpenMesh flag the vertex copies it makes at non-manifold faces
    OpenMesh::IO::Options options;
    bool ok = false;
    std::string messages;
    {
        OpenMeshMessages capture;
        ok = OpenMesh::IO::read_mesh(pm, path, options);
        messages = capture.text();
    }
    if (!ok) throw file_error(path, "OpenMesh cannot read it as " + format + first_line(messages));
    if (const std::size_t bad = count_occurrences(messages, "invalid vertex index"))
        throw file_error(path, std::to_string(bad) +
                                   " face(s) reference a vertex that does not exist (or a vertex line was unreadable, "
                                   "e.g. 'nan', which shifts the indices)");

    MeshBuilder builder;
    builder.skipped_faces = count_occurrences(messages, "equal vertices"); // OpenMesh dropped these already
    const std::vector<int> index = weld_nonmanifold_copies(pm, builder.mesh.vertices);
    std::vector<int> corners;
    for (const auto f : pm.faces()) {
        corners.clear();
        for (const auto v : pm.fv_range(f)) corners.push_back(index[static_cast<std::size_t>(v.idx())]);
        builder.add_polygon(corners);
    }
    return builder.finish(path);
}

} // namespace vox::io::detail
