#include "grid/label_grid_vdb.hpp"

#include "core/atomic_file.hpp"
#include "core/child_process.hpp"
#include "core/error.hpp"
#include "core/memory_limit.hpp"
#include "grid/voxel_limits.hpp"

#include <openvdb/io/File.h>
#include <openvdb/io/Stream.h>

#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <mutex>
#include <sstream>

namespace vox::grid {

void ensure_openvdb_initialized()
{
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}

openvdb::math::Transform::Ptr to_vdb_transform(const Eigen::Matrix4d& t)
{
    openvdb::math::Mat4d m; // row-vector convention: world = index * m
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) m(c, r) = t(r, c);
    return openvdb::math::Transform::createLinearTransform(m);
}

Eigen::Matrix4d from_vdb_transform(const openvdb::math::Transform& xform)
{
    const openvdb::math::Mat4d m = xform.baseMap()->getAffineMap()->getMat4();
    Eigen::Matrix4d t;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) t(r, c) = m(c, r);
    return t;
}

LabelGrid::LabelGrid(const Eigen::Matrix4d& index_to_world)
{
    ensure_openvdb_initialized();
    auto g = openvdb::Int32Grid::create(0);
    g->setName("labels");
    g->setTransform(to_vdb_transform(index_to_world));
    m_impl = std::make_unique<Impl>(g);
}

LabelGrid::~LabelGrid() = default;
LabelGrid::LabelGrid(LabelGrid&&) noexcept = default;
LabelGrid& LabelGrid::operator=(LabelGrid&&) noexcept = default;

LabelGrid LabelGrid::clone() const { return from_vdb(m_impl->grid->deepCopy()); }

Eigen::Matrix4d LabelGrid::index_to_world() const { return from_vdb_transform(m_impl->grid->transform()); }

Eigen::Vector3d LabelGrid::voxel_size() const
{
    return index_to_world().topLeftCorner<3, 3>().colwise().norm().transpose();
}

Eigen::Vector3d LabelGrid::index_to_world(const Eigen::Vector3d& ijk) const
{
    const openvdb::Vec3d w = m_impl->grid->transform().indexToWorld(openvdb::Vec3d(ijk.x(), ijk.y(), ijk.z()));
    return {w.x(), w.y(), w.z()};
}

void LabelGrid::set(const Coord& ijk, std::int32_t label)
{
    const openvdb::Coord c(ijk.x(), ijk.y(), ijk.z());
    if (label == 0)
        m_impl->accessor.setValueOff(c, 0);
    else
        m_impl->accessor.setValueOn(c, label);
}

std::int32_t LabelGrid::get(const Coord& ijk) const
{
    const openvdb::Coord c(ijk.x(), ijk.y(), ijk.z());
    std::int32_t v = 0;
    return m_impl->accessor.probeValue(c, v) ? v : 0;
}

std::uint64_t LabelGrid::active_voxel_count() const { return m_impl->grid->activeVoxelCount(); }

IndexBox LabelGrid::index_bounds() const
{
    IndexBox box;
    if (m_impl->grid->activeVoxelCount() == 0) return box;
    const openvdb::CoordBBox b = m_impl->grid->evalActiveVoxelBoundingBox();
    box.min = {b.min().x(), b.min().y(), b.min().z()};
    box.max = {b.max().x(), b.max().y(), b.max().z()};
    return box;
}

std::map<std::int32_t, std::uint64_t> LabelGrid::label_histogram() const
{
    std::map<std::int32_t, std::uint64_t> hist;
    for (auto it = m_impl->grid->cbeginValueOn(); it; ++it) {
        if (it.isVoxelValue())
            ++hist[*it];
        else
            hist[*it] += it.getVoxelCount(); // an active tile: a whole block with one label
    }
    return hist;
}

void LabelGrid::for_each_active(const std::function<void(const Coord&, std::int32_t)>& f) const
{
    for (auto it = m_impl->grid->cbeginValueOn(); it; ++it) {
        if (it.isVoxelValue()) {
            const openvdb::Coord c = it.getCoord();
            f(Coord(c.x(), c.y(), c.z()), *it);
            continue;
        }
        openvdb::CoordBBox bbox;
        it.getBoundingBox(bbox);
        for (auto c = bbox.begin(); c; ++c) f(Coord((*c).x(), (*c).y(), (*c).z()), *it);
    }
}

void LabelGrid::set_metadata(const std::string& key, const std::string& value)
{
    m_impl->grid->insertMeta(key, openvdb::StringMetadata(value));
}

void LabelGrid::copy_metadata(const LabelGrid& from)
{
    for (auto it = from.m_impl->grid->beginMeta(); it != from.m_impl->grid->endMeta(); ++it)
        if (it->second && it->second->typeName() == openvdb::StringMetadata::staticTypeName())
            m_impl->grid->insertMeta(it->first, *it->second);
}

std::string LabelGrid::metadata(const std::string& key) const
{
    const auto meta = m_impl->grid->getMetadata<openvdb::StringMetadata>(key);
    return meta ? meta->value() : std::string();
}

void LabelGrid::save(const std::filesystem::path& path) const
{
    write_atomically(path, [&](const std::filesystem::path& tmp) {
        openvdb::io::File file(tmp.string());
        openvdb::GridPtrVec grids{m_impl->grid};
        try {
            file.write(grids);
            file.close();
        } catch (const openvdb::Exception& e) {
            throw file_error(path.string(), std::string("cannot write: ") + e.what());
        }
    });
}

namespace {

/// The label grid of an OpenVDB file's grids: the int32 grid named "labels", else the first int32
/// grid; null when there is none.
openvdb::Int32Grid::Ptr label_grid_of(const openvdb::GridPtrVec& grids)
{
    openvdb::Int32Grid::Ptr found;
    for (const auto& g : grids) {
        auto ig = openvdb::gridPtrCast<openvdb::Int32Grid>(g);
        if (!ig) continue;
        if (!found || ig->getName() == "labels") found = ig;
    }
    return found;
}

/// The wall time a child may take to read `bytes` of .vdb: far more than a sound file needs (tens of
/// milliseconds for the bundled ones; OpenVDB reads hundreds of MB a second).
double read_seconds_allowed(std::uint64_t bytes) { return 3.0 + 0.1 * static_cast<double>(bytes >> 20); }

/// A reader's own message made fit for one line: a corrupt file can put its garbage into it
/// (OpenVDB names the unknown map type it read), so control and non-ASCII bytes become '?',
/// runs of white space one space, and it stops after 160 characters.
/// The start of the refusal of a file without a label grid.
const std::string k_no_label_grid = "holds no int32 label grid (found ";
/// The start of the refusal of a grid whose transform OpenVDB cannot turn into a matrix.
const std::string k_unusable_transform = "its grid transform is unusable (";

std::string one_line(const std::string& text)
{
    std::string out;
    for (const char c : text) {
        const auto u = static_cast<unsigned char>(c);
        if (u == ' ' || u == '\t' || u == '\n' || u == '\r') {
            if (!out.empty() && out.back() != ' ') out += ' ';
        } else {
            out += (u < 32 || u > 126) ? '?' : c;
        }
        if (out.size() >= 160) return out + "...";
    }
    while (!out.empty() && out.back() == ' ') out.pop_back();
    return out;
}

/// The label grid of `in` (a .vdb's bytes), read in a child process and handed back written
/// again by OpenVDB's own writer. OpenVDB's reader trusts the counts in a file, so a corrupt one
/// can crash it, spin for ever, allocate gigabytes, or overrun a buffer that only a later free
/// notices (a file with 7 bytes inserted read "cleanly", then aborted this process with "corrupted
/// size vs. prev_size" long after). So this process never reads the file itself: only what
/// OpenVDB wrote, from a grid the child read cleanly, within the memory limit and in time.
std::string label_grid_read_in_child(std::istringstream& in, const std::string& name, std::uint64_t bytes)
{
    const int fd = memfd_create("voxsculpt-vdb", MFD_CLOEXEC);
    if (fd < 0) throw file_error(name, std::string("cannot be read: memfd_create: ") + std::strerror(errno));
    struct Closer {
        int fd;
        ~Closer() { close(fd); }
    } closer{fd};
    const ChildLimits limits{memory_limit_bytes(), read_seconds_allowed(bytes), true};
    const ChildOutcome outcome = run_in_child(
        [&] {
            openvdb::io::Stream stream(in);
            const openvdb::GridPtrVecPtr grids = stream.getGrids();
            const openvdb::Int32Grid::Ptr grid = label_grid_of(*grids);
            if (!grid) throw std::runtime_error(k_no_label_grid + std::to_string(grids->size()) + " grid(s) of other types)");
            static_cast<void>(grid->activeVoxelCount()); // walks every node of the tree
            try { // a transform OpenVDB stored but cannot turn into a matrix (a zero scale) cannot be written either
                static_cast<void>(from_vdb_transform(grid->transform()));
            } catch (const openvdb::Exception& e) {
                throw std::runtime_error(k_unusable_transform + std::string(e.what()) + ")");
            }
            std::ostringstream out;
            openvdb::io::Stream(out).write(openvdb::GridCPtrVec{grid});
            const std::string written = out.str();
            for (std::size_t at = 0; at < written.size();) {
                const ssize_t n = write(fd, written.data() + at, written.size() - at);
                if (n <= 0) throw std::runtime_error(std::string("cannot hand the grid back: ") + std::strerror(errno));
                at += static_cast<std::size_t>(n);
            }
        },
        limits);
    const std::string corrupt = "not a readable OpenVDB file: ";
    switch (outcome.kind) {
    case ChildOutcome::Kind::ok: break;
    case ChildOutcome::Kind::failed:
        if (outcome.message.rfind(k_no_label_grid, 0) == 0 || outcome.message.rfind(k_unusable_transform, 0) == 0)
            throw file_error(name, one_line(outcome.message));
        throw file_error(name, "not a readable OpenVDB file (" + one_line(outcome.message) + ")");
    case ChildOutcome::Kind::out_of_memory:
        throw file_error(name, corrupt + "reading it needs more than the memory limit of " +
                                   std::to_string(memory_limit_bytes() >> 20) +
                                   " MiB (corrupt, or set --max-memory-mb to raise it)");
    case ChildOutcome::Kind::timed_out:
        throw file_error(name, corrupt + "OpenVDB's reader did not finish within " +
                                   std::to_string(static_cast<int>(limits.seconds)) + " s (the file is corrupt)");
    case ChildOutcome::Kind::crashed:
        throw file_error(name, corrupt + "OpenVDB's reader crashed on it (" + signal_name(outcome.signal) +
                                   "; the file is corrupt)");
    }
    const off_t size = lseek(fd, 0, SEEK_END);
    if (size < 0 || lseek(fd, 0, SEEK_SET) != 0) throw file_error(name, std::string("cannot be read: ") + std::strerror(errno));
    std::string clean(static_cast<std::size_t>(size), '\0');
    for (std::size_t at = 0; at < clean.size();) {
        const ssize_t n = read(fd, clean.data() + at, clean.size() - at);
        if (n <= 0) throw file_error(name, std::string("cannot be read: ") + std::strerror(errno));
        at += static_cast<std::size_t>(n);
    }
    return clean;
}

} // namespace

LabelGrid LabelGrid::load(const std::filesystem::path& path)
{
    ensure_openvdb_initialized();
    const std::string name = path.string();
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw file_error(name, "no such file");
    const std::uint64_t size = std::filesystem::file_size(path, ec);
    if (ec) throw file_error(name, "cannot read its size: " + ec.message());
    check_allocation(name, size, 1);
    std::string bytes(size, '\0');
    {
        std::ifstream file(path, std::ios::binary);
        file.read(bytes.data(), static_cast<std::streamsize>(size));
        if (!file || static_cast<std::uint64_t>(file.gcount()) != size) throw file_error(name, "cannot read it");
    }
    std::istringstream in(std::move(bytes));
    std::istringstream clean(label_grid_read_in_child(in, name, size));
    openvdb::GridPtrVecPtr grids;
    try {
        openvdb::io::Stream stream(clean);
        grids = stream.getGrids();
    } catch (const std::exception& e) { // not expected: OpenVDB reading what it wrote itself
        throw file_error(name, "not a readable OpenVDB file (" + one_line(e.what()) + ")");
    }
    openvdb::Int32Grid::Ptr found = label_grid_of(*grids);
    if (!found) throw file_error(name, "holds no int32 label grid after all (an error of OpenVDB's reader or writer)");
    if (!found->transform().isLinear()) throw file_error(name, "the grid's transform is not affine");
    found->setName("labels");
    // A transform no scan has: refused as a scan's would be (io/volume.cpp). Found by fuzzing.
    const Eigen::Matrix4d t = from_vdb_transform(found->transform()); // the child checked that it converts
    const Eigen::Vector3d spacing = t.topLeftCorner<3, 3>().colwise().norm();
    if (!t.allFinite() || !(spacing.minCoeff() >= k_min_voxel_mm) || !(t.topRightCorner<3, 1>().cwiseAbs().maxCoeff() <= k_max_world_mm))
        throw file_error(name, "its grid transform is not a scan's: voxel sizes below 0.0001 mm, an origin beyond 1e6 mm or a "
                               "number that is not finite");
    return from_vdb(found);
}

openvdb::Int32Grid::Ptr vdb_grid(const LabelGrid& labels) { return labels.impl().grid; }

LabelGrid from_vdb(openvdb::Int32Grid::Ptr grid)
{
    LabelGrid out(from_vdb_transform(grid->transform()));
    out.impl().reset(std::move(grid));
    return out;
}

} // namespace vox::grid
