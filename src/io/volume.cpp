#include "io/volume.hpp"

#include "core/error.hpp"
#include "grid/voxel_limits.hpp"
#include "io/text_parsing.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>

namespace vox::io {

std::string NiftiTransforms::text() const
{
    std::ostringstream out;
    out.precision(17);
    out << sform_code << ' ' << qform_code;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) out << ' ' << qform_ras(r, c);
    return out.str();
}

std::optional<NiftiTransforms> NiftiTransforms::parse(const std::string& text)
{
    std::istringstream in(text);
    NiftiTransforms t;
    if (!(in >> t.sform_code >> t.qform_code)) return std::nullopt;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c)
            if (!(in >> t.qform_ras(r, c))) return std::nullopt;
    if (!(in >> std::ws).eof() || !t.qform_ras.allFinite()) return std::nullopt;
    return t;
}

std::size_t scalar_size(ScalarType t)
{
    switch (t) {
    case ScalarType::u8:
    case ScalarType::i8: return 1;
    case ScalarType::u16:
    case ScalarType::i16: return 2;
    case ScalarType::u32:
    case ScalarType::i32:
    case ScalarType::f32: return 4;
    case ScalarType::f64: return 8;
    }
    return 1;
}

const char* scalar_name(ScalarType t)
{
    switch (t) {
    case ScalarType::u8: return "uint8";
    case ScalarType::i8: return "int8";
    case ScalarType::u16: return "uint16";
    case ScalarType::i16: return "int16";
    case ScalarType::u32: return "uint32";
    case ScalarType::i32: return "int32";
    case ScalarType::f32: return "float32";
    case ScalarType::f64: return "float64";
    }
    return "?";
}

bool is_integer(ScalarType t) { return t != ScalarType::f32 && t != ScalarType::f64; }

namespace {
template <class T> double load(const std::byte* p)
{
    T v;
    std::memcpy(&v, p, sizeof(T));
    return static_cast<double>(v);
}
} // namespace

double Volume::stored(std::int64_t n) const
{
    const std::byte* p = data.data() + static_cast<std::size_t>(n) * scalar_size(type);
    switch (type) {
    case ScalarType::u8: return load<std::uint8_t>(p);
    case ScalarType::i8: return load<std::int8_t>(p);
    case ScalarType::u16: return load<std::uint16_t>(p);
    case ScalarType::i16: return load<std::int16_t>(p);
    case ScalarType::u32: return load<std::uint32_t>(p);
    case ScalarType::i32: return load<std::int32_t>(p);
    case ScalarType::f32: return load<float>(p);
    case ScalarType::f64: return load<double>(p);
    }
    return 0.0;
}

Eigen::Vector3d Volume::spacing() const { return index_to_world.topLeftCorner<3, 3>().colwise().norm().transpose(); }

void validate(const Volume& v)
{
    for (int a = 0; a < 3; ++a)
        if (v.dims[a] <= 0)
            throw file_error(v.source, "dimension " + std::to_string(a) + " is " + std::to_string(v.dims[a]) +
                                           " (must be positive)");
    if (!v.index_to_world.allFinite()) throw file_error(v.source, "the index-to-world transform is not finite");
    const Eigen::Vector3d s = v.spacing();
    // The limits every grid takes (grid/voxel_limits.hpp).
    for (int a = 0; a < 3; ++a) {
        if (!(s[a] > 0.0)) throw file_error(v.source, "voxel spacing along axis " + std::to_string(a) + " is zero");
        if (s[a] < grid::k_min_voxel_mm)
            throw file_error(v.source, "voxel spacing along axis " + std::to_string(a) + " is " + detail::number_text(s[a]) +
                                           " mm, below the 0.0001 mm (0.1 micrometre) limit");
    }
    if (std::abs(v.index_to_world.topLeftCorner<3, 3>().determinant()) <= 1e-12 * s.prod())
        throw file_error(v.source, "the voxel axes are degenerate (direction matrix is singular)");
    for (int corner = 0; corner < 8; ++corner) {
        const Eigen::Vector4d index((corner & 1) ? v.dims[0] : 0, (corner & 2) ? v.dims[1] : 0,
                                    (corner & 4) ? v.dims[2] : 0, 1.0);
        const double far = (v.index_to_world * index).head<3>().cwiseAbs().maxCoeff();
        if (!(far <= grid::k_max_world_mm))
            throw file_error(v.source, "its voxels lie up to " + detail::number_text(far) +
                                           " mm from the origin, beyond the 1e6 mm (1 km) limit: check its origin and spacing");
    }
    if (!std::isfinite(v.scale_slope) || !std::isfinite(v.scale_intercept))
        throw file_error(v.source, "the value scaling (slope/intercept) is not finite");
    const auto expect = static_cast<std::size_t>(v.voxel_count()) * scalar_size(v.type);
    if (v.data.size() != expect)
        throw file_error(v.source, "holds " + std::to_string(v.data.size()) + " bytes of voxels, expected " +
                                       std::to_string(expect));
}

void check_voxel_bytes(const Volume& v, std::uint64_t held, const std::string& what)
{
    const std::uint64_t bytes = static_cast<std::uint64_t>(v.voxel_count()) * scalar_size(v.type);
    const std::string describe = std::to_string(v.dims[0]) + "x" + std::to_string(v.dims[1]) + "x" +
                                 std::to_string(v.dims[2]) + " " + scalar_name(v.type);
    if (held < bytes)
        throw file_error(what, "truncated: holds " + std::to_string(held) + " bytes of voxel data, " + describe +
                                   " needs " + std::to_string(bytes));
    if (held > bytes)
        throw file_error(what, "holds " + std::to_string(held) + " bytes of voxel data, more than the " +
                                   std::to_string(bytes) + " of " + describe +
                                   ": the header does not describe this data");
}

void swap_bytes(Volume& v)
{
    const std::size_t w = scalar_size(v.type);
    if (w == 1) return;
    for (std::size_t i = 0; i + w <= v.data.size(); i += w) std::reverse(v.data.begin() + i, v.data.begin() + i + w);
}

Eigen::Matrix4d make_index_to_world(const Eigen::Vector3d& spacing, const Eigen::Matrix3d& direction,
                                    const Eigen::Vector3d& origin)
{
    Eigen::Matrix4d t = Eigen::Matrix4d::Identity();
    t.topLeftCorner<3, 3>() = direction * spacing.asDiagonal();
    t.topRightCorner<3, 1>() = origin;
    return t;
}

} // namespace vox::io
