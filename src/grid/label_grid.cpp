#include "grid/label_grid_vdb.hpp"

#include "core/atomic_file.hpp"
#include "core/error.hpp"

#include <openvdb/io/File.h>

#include <mutex>

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

LabelGrid LabelGrid::load(const std::filesystem::path& path)
{
    ensure_openvdb_initialized();
    const std::string name = path.string();
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw file_error(name, "no such file");
    openvdb::GridPtrVecPtr grids;
    try {
        openvdb::io::File file(name);
        file.open(false); // no delayed loading: the file may be replaced while we run
        grids = file.getGrids();
        file.close();
    } catch (const std::exception& e) {
        throw file_error(name, std::string("not a readable OpenVDB file (") + e.what() + ")");
    }
    openvdb::Int32Grid::Ptr found;
    for (const auto& g : *grids) {
        auto ig = openvdb::gridPtrCast<openvdb::Int32Grid>(g);
        if (!ig) continue;
        if (!found || ig->getName() == "labels") found = ig;
    }
    if (!found) throw file_error(name, "holds no int32 label grid (found " + std::to_string(grids->size()) + " grid(s) of other types)");
    if (!found->transform().isLinear()) throw file_error(name, "the grid's transform is not affine");
    found->setName("labels");
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
