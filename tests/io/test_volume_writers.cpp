#include "io/test_volume_writers.hpp"

#include <nifti2_io.h>
#include <zlib.h>

#include <bit>
#include <charconv>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace vox::test {
namespace {

/// Shortest text that reads back as exactly the same double (std::to_chars round-trip guarantee),
/// so headers carry the transform to the last bit.
std::string num(double x)
{
    char buf[32];
    const auto [end, ec] = std::to_chars(buf, buf + sizeof(buf), x);
    if (ec != std::errc()) throw std::runtime_error("cannot format a number");
    return {buf, end};
}

bool ends_with(const std::string& s, const std::string& suffix)
{
    return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

/// The voxel bytes in little-endian order, whatever the host.
std::vector<std::byte> little_endian_bytes(const io::Volume& v)
{
    io::Volume copy = v;
    if (std::endian::native == std::endian::big) io::swap_bytes(copy);
    return copy.data;
}

/// zlib (`gzip == false`, as MetaIO's CompressedData) or gzip (as NRRD's gzip encoding) stream.
std::vector<std::byte> deflate_bytes(const std::vector<std::byte>& in, bool gzip)
{
    z_stream zs{};
    if (deflateInit2(&zs, Z_BEST_COMPRESSION, Z_DEFLATED, gzip ? 15 + 16 : 15, 8, Z_DEFAULT_STRATEGY) != Z_OK)
        throw std::runtime_error("deflateInit2 failed");
    std::vector<std::byte> out(deflateBound(&zs, static_cast<uLong>(in.size())) + 32);
    zs.next_in = reinterpret_cast<Bytef*>(const_cast<std::byte*>(in.data()));
    zs.avail_in = static_cast<uInt>(in.size());
    zs.next_out = reinterpret_cast<Bytef*>(out.data());
    zs.avail_out = static_cast<uInt>(out.size());
    const int rc = deflate(&zs, Z_FINISH);
    out.resize(zs.total_out);
    deflateEnd(&zs);
    if (rc != Z_STREAM_END) throw std::runtime_error("deflate failed");
    return out;
}

void write_file(const std::string& path, const std::string& header, const std::vector<std::byte>& data)
{
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(header.data(), static_cast<std::streamsize>(header.size()));
    out.write(reinterpret_cast<const char*>(data.data()), static_cast<std::streamsize>(data.size()));
    if (!out) throw std::runtime_error("cannot write " + path);
}

/// Spacing (column norms) and unit direction columns of the volume's linear part.
void split_transform(const io::Volume& v, Eigen::Vector3d& spacing, Eigen::Matrix3d& direction)
{
    const Eigen::Matrix3d linear = v.index_to_world.topLeftCorner<3, 3>();
    spacing = linear.colwise().norm().transpose();
    direction = linear * spacing.cwiseInverse().asDiagonal();
}

const char* metaio_type(io::ScalarType t)
{
    switch (t) {
    case io::ScalarType::u8: return "MET_UCHAR";
    case io::ScalarType::i8: return "MET_CHAR";
    case io::ScalarType::u16: return "MET_USHORT";
    case io::ScalarType::i16: return "MET_SHORT";
    case io::ScalarType::u32: return "MET_UINT";
    case io::ScalarType::i32: return "MET_INT";
    case io::ScalarType::f32: return "MET_FLOAT";
    case io::ScalarType::f64: return "MET_DOUBLE";
    }
    return "?";
}

const char* nrrd_type(io::ScalarType t)
{
    switch (t) {
    case io::ScalarType::u8: return "uint8";
    case io::ScalarType::i8: return "int8";
    case io::ScalarType::u16: return "ushort";
    case io::ScalarType::i16: return "short";
    case io::ScalarType::u32: return "unsigned int";
    case io::ScalarType::i32: return "int32_t";
    case io::ScalarType::f32: return "float";
    case io::ScalarType::f64: return "double";
    }
    return "?";
}

int nifti_type(io::ScalarType t)
{
    switch (t) {
    case io::ScalarType::u8: return DT_UINT8;
    case io::ScalarType::i8: return DT_INT8;
    case io::ScalarType::u16: return DT_UINT16;
    case io::ScalarType::i16: return DT_INT16;
    case io::ScalarType::u32: return DT_UINT32;
    case io::ScalarType::i32: return DT_INT32;
    case io::ScalarType::f32: return DT_FLOAT32;
    case io::ScalarType::f64: return DT_FLOAT64;
    }
    return DT_UNKNOWN;
}

} // namespace

void write_nifti(const io::Volume& v, const std::string& path)
{
    const std::int64_t dims[8] = {3, v.dims[0], v.dims[1], v.dims[2], 1, 1, 1, 1};
    std::unique_ptr<nifti_image, void (*)(nifti_image*)> nim(nifti_make_new_nim(dims, nifti_type(v.type), 1),
                                                             nifti_image_free);
    if (!nim) throw std::runtime_error("nifti_make_new_nim failed");
    std::memcpy(nim->data, v.data.data(), v.data.size());

    // NIfTI's world is RAS: negate the LPS x and y rows.
    const Eigen::Matrix4d ras = Eigen::Vector4d(-1.0, -1.0, 1.0, 1.0).asDiagonal() * v.index_to_world;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) nim->sto_xyz.m[r][c] = ras(r, c);
    nim->sto_ijk = nifti_dmat44_inverse(nim->sto_xyz);
    nim->sform_code = NIFTI_XFORM_SCANNER_ANAT;

    Eigen::Vector3d spacing;
    Eigen::Matrix3d direction;
    split_transform(v, spacing, direction);
    nim->dx = nim->pixdim[1] = spacing.x();
    nim->dy = nim->pixdim[2] = spacing.y();
    nim->dz = nim->pixdim[3] = spacing.z();
    // The qform can only hold a rotation (with an optional flip of k): write it when that is what we have.
    if ((direction.transpose() * direction - Eigen::Matrix3d::Identity()).norm() < 1e-9) {
        nifti_dmat44_to_quatern(nim->sto_xyz, &nim->quatern_b, &nim->quatern_c, &nim->quatern_d, &nim->qoffset_x,
                                &nim->qoffset_y, &nim->qoffset_z, nullptr, nullptr, nullptr, &nim->qfac);
        nim->pixdim[0] = nim->qfac;
        nim->qto_xyz = nifti_quatern_to_dmat44(nim->quatern_b, nim->quatern_c, nim->quatern_d, nim->qoffset_x,
                                               nim->qoffset_y, nim->qoffset_z, nim->dx, nim->dy, nim->dz, nim->qfac);
        nim->qto_ijk = nifti_dmat44_inverse(nim->qto_xyz);
        nim->qform_code = NIFTI_XFORM_SCANNER_ANAT;
    }
    nim->xyz_units = NIFTI_UNITS_MM;
    nim->scl_slope = v.scale_slope;
    nim->scl_inter = v.scale_intercept;

    if (nifti_set_filenames(nim.get(), path.c_str(), 0, 1) != 0) throw std::runtime_error("bad NIfTI path " + path);
    nifti_image_write(nim.get());
    if (!std::filesystem::exists(path)) throw std::runtime_error("libnifti2 did not write " + path);
}

void write_metaimage(const io::Volume& v, const std::string& path, bool compressed)
{
    const bool local = ends_with(path, ".mha");
    if (!local && !ends_with(path, ".mhd"))
        throw std::invalid_argument("MetaImage path must end in .mha or .mhd: " + path);
    Eigen::Vector3d spacing;
    Eigen::Matrix3d direction;
    split_transform(v, spacing, direction);
    const std::vector<std::byte> raw = little_endian_bytes(v);
    const std::vector<std::byte> data = compressed ? deflate_bytes(raw, false) : raw;

    std::ostringstream h;
    h << "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\n";
    h << "CompressedData = " << (compressed ? "True" : "False") << "\n";
    if (compressed) h << "CompressedDataSize = " << data.size() << "\n";
    // MetaIO's TransformMatrix lists index axis a's direction as values [3a .. 3a+2].
    h << "TransformMatrix =";
    for (int a = 0; a < 3; ++a)
        for (int r = 0; r < 3; ++r) h << ' ' << num(direction(r, a));
    h << "\nOffset = " << num(v.index_to_world(0, 3)) << ' ' << num(v.index_to_world(1, 3)) << ' '
      << num(v.index_to_world(2, 3)) << "\n";
    h << "CenterOfRotation = 0 0 0\n";
    h << "ElementSpacing = " << num(spacing.x()) << ' ' << num(spacing.y()) << ' ' << num(spacing.z()) << "\n";
    h << "DimSize = " << v.dims[0] << ' ' << v.dims[1] << ' ' << v.dims[2] << "\n";
    h << "ElementType = " << metaio_type(v.type) << "\n";
    if (local) {
        h << "ElementDataFile = LOCAL\n";
        write_file(path, h.str(), data);
        return;
    }
    const std::filesystem::path data_path =
        std::filesystem::path(path).replace_extension(compressed ? ".zraw" : ".raw");
    h << "ElementDataFile = " << data_path.filename().string() << "\n";
    write_file(path, h.str(), {});
    write_file(data_path.string(), "", data);
}

void write_nrrd(const io::Volume& v, const std::string& path, const std::string& encoding)
{
    if (encoding != "raw" && encoding != "gzip") throw std::invalid_argument("NRRD encoding must be raw or gzip");
    const std::vector<std::byte> raw = little_endian_bytes(v);
    const std::vector<std::byte> data = encoding == "gzip" ? deflate_bytes(raw, true) : raw;

    std::ostringstream h;
    h << "NRRD0004\n# written by VoxSculpt's test writers\n";
    h << "type: " << nrrd_type(v.type) << "\ndimension: 3\nspace: left-posterior-superior\n";
    h << "sizes: " << v.dims[0] << ' ' << v.dims[1] << ' ' << v.dims[2] << "\n";
    h << "space directions:";
    for (int a = 0; a < 3; ++a)
        h << " (" << num(v.index_to_world(0, a)) << ',' << num(v.index_to_world(1, a)) << ','
          << num(v.index_to_world(2, a)) << ')';
    h << "\nkinds: domain domain domain\nendian: little\nencoding: " << encoding << "\n";
    h << "space origin: (" << num(v.index_to_world(0, 3)) << ',' << num(v.index_to_world(1, 3)) << ','
      << num(v.index_to_world(2, 3)) << ")\n";
    if (!ends_with(path, ".nhdr")) {
        h << "\n";
        write_file(path, h.str(), data);
        return;
    }
    const std::filesystem::path data_path =
        std::filesystem::path(path).replace_extension(encoding == "gzip" ? ".raw.gz" : ".raw");
    h << "data file: " << data_path.filename().string() << "\n";
    write_file(path, h.str(), {});
    write_file(data_path.string(), "", data);
}

void write_inr(const io::Volume& v, const std::string& path)
{
    const Eigen::Matrix3d linear = v.index_to_world.topLeftCorner<3, 3>();
    if (!linear.isDiagonal() || (linear.diagonal().array() <= 0.0).any())
        throw std::invalid_argument("INRIMAGE-4 holds only axis-aligned volumes with positive spacing");
    const char* type = "";
    switch (v.type) {
    case io::ScalarType::u8:
    case io::ScalarType::u16:
    case io::ScalarType::u32: type = "unsigned fixed"; break;
    case io::ScalarType::i8:
    case io::ScalarType::i16:
    case io::ScalarType::i32: type = "signed fixed"; break;
    case io::ScalarType::f32:
    case io::ScalarType::f64: type = "float"; break;
    }
    std::ostringstream h;
    h << "#INRIMAGE-4#{\nXDIM=" << v.dims[0] << "\nYDIM=" << v.dims[1] << "\nZDIM=" << v.dims[2] << "\nVDIM=1\n";
    h << "TYPE=" << type << "\nPIXSIZE=" << 8 * io::scalar_size(v.type) << " bits\nSCALE=2**0\nCPU=decm\n";
    h << "VX=" << num(linear(0, 0)) << "\nVY=" << num(linear(1, 1)) << "\nVZ=" << num(linear(2, 2)) << "\n";
    h << "XO=" << num(v.index_to_world(0, 3)) << "\nYO=" << num(v.index_to_world(1, 3))
      << "\nZO=" << num(v.index_to_world(2, 3)) << "\n";
    std::string header = h.str();
    constexpr std::string_view end = "##}\n";
    if (header.size() + end.size() > 256) throw std::runtime_error("INR header does not fit in 256 bytes");
    header.append(256 - end.size() - header.size(), '\n');
    header += end;
    write_file(path, header, little_endian_bytes(v));
}

std::string le16(std::initializer_list<std::int16_t> values)
{
    std::string out;
    for (const std::int16_t v : values) {
        const auto u = static_cast<std::uint16_t>(v);
        out += static_cast<char>(u & 0xff);
        out += static_cast<char>(u >> 8);
    }
    return out;
}

std::string be16(std::initializer_list<std::int16_t> values)
{
    std::string out = le16(values);
    for (std::size_t i = 0; i + 1 < out.size(); i += 2) std::swap(out[i], out[i + 1]);
    return out;
}

std::string gzip(const std::string& data)
{
    const auto* first = reinterpret_cast<const std::byte*>(data.data());
    const std::vector<std::byte> zipped = deflate_bytes(std::vector<std::byte>(first, first + data.size()), true);
    return {reinterpret_cast<const char*>(zipped.data()), zipped.size()};
}

Eigen::Vector3d world(const io::Volume& v, double i, double j, double k)
{
    return (v.index_to_world * Eigen::Vector4d(i, j, k, 1.0)).head<3>();
}

} // namespace vox::test
