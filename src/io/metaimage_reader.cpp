// MetaImage reader (.mha with the voxels after the header, .mhd with a separate data file), following
// ITK's MetaIO (Modules/ThirdParty/MetaIO metaObject.cxx / metaImage.cxx, Modules/IO/Meta
// itkMetaImageIO.cxx):
//
// - The header is "Key = value" lines, keys case-sensitive as MetaIO writes them, ending with the
//   ElementDataFile line; LOCAL data starts on the byte after that line.
// - Offset (aliases Origin, Position) is the world position of voxel (0,0,0)'s centre, in mm.
// - TransformMatrix (aliases Rotation, Orientation) holds NDims x NDims numbers; ITK's
//   MetaImageIO::ReadImageInformation passes values [a*N .. a*N+N-1] to SetDirection(a, ...), so
//   they are the world direction of index axis a, i.e. a COLUMN of the direction matrix.
// - ElementSpacing is the voxel spacing; ElementSize stands in for it only when ElementSpacing is
//   absent (metaImage.cxx M_Read); neither means 1.
// - AnatomicalOrientation is ignored, as ITK ignores it: the world frame is ITK's LPS whatever it says.
// - ElementToIntensityFunctionSlope/Offset are ignored, as ITK ignores them: values are read as stored.
// - HeaderSize N > 0 puts the data at byte N of the data file (for LOCAL, of the .mha itself);
//   HeaderSize = -1 puts it at the end of the data file.
// - NDims 2 is read as a single slice (third axis along the normal, spacing 1 mm).
//
// Stricter than MetaIO: several aliases of one key that disagree, duplicate keys, a data file longer
// than the header describes (the header then does not describe the data) are refused; so are
// ASCII voxel data (BinaryData = False), several channels, LIST and %d slice-file patterns.

#include "core/error.hpp"
#include "core/memory_limit.hpp"
#include "io/file_bytes.hpp"
#include "io/text_parsing.hpp"
#include "io/volume_reader.hpp"

#include <algorithm>
#include <bit>
#include <filesystem>
#include <limits>
#include <map>
#include <optional>
#include <string_view>

namespace vox::io {

using detail::field_double;
using detail::field_int;
using detail::HeaderFields;
using detail::number_text;
using detail::printable;
using detail::split_words;
using detail::trim;

namespace {

/// MetaImage headers are a few hundred bytes: a file with no ElementDataFile line in its first MiB
/// is not one, and reading further would only pull binary data into memory.
constexpr std::size_t k_max_header_bytes = std::size_t{1} << 20;

/// MetaImage values are separated by blanks and tabs.
constexpr std::string_view k_separators = " \t";

/// The header's keys and values, and the byte offset just past the ElementDataFile line.
HeaderFields read_header(const std::string& path)
{
    const auto [text, whole_file] = read_file_head(path, k_max_header_bytes);
    HeaderFields h;
    std::size_t pos = 0;
    for (int line_no = 1; pos < text.size(); ++line_no) {
        auto nl = text.find('\n', pos);
        // A last line without a newline is complete only when the whole file was read.
        if (nl == std::string::npos && !whole_file) break;
        if (nl == std::string::npos) nl = text.size();
        const std::string_view line = trim(std::string_view(text).substr(pos, nl - pos));
        pos = std::min(nl + 1, text.size());
        if (line.empty()) continue;
        const auto eq = line.find('=');
        if (detail::is_binary(line))
            throw file_error(path, "not a MetaImage header: line " + std::to_string(line_no) +
                                       " holds binary data, not 'Key = value' text");
        if (eq == std::string_view::npos || trim(line.substr(0, eq)).empty())
            throw file_error(path, "not a MetaImage header: line " + std::to_string(line_no) +
                                       " is not 'Key = value' ('" + printable(line) + "')");
        const std::string key(trim(line.substr(0, eq)));
        if (!h.fields.emplace(key, std::string(trim(line.substr(eq + 1)))).second)
            throw file_error(path, "header key '" + key + "' appears twice");
        if (key == "ElementDataFile") {
            h.end = pos;
            return h;
        }
    }
    throw file_error(path, std::string("not a MetaImage header: no 'ElementDataFile' line") +
                               (whole_file ? "" : " in its first MiB"));
}

/// The numbers of `key`, which must hold exactly `count` of them; nullopt when the key is absent.
std::optional<std::vector<double>> numbers(const std::string& path, const HeaderFields& h, std::string_view key,
                                           std::size_t count, const std::string& why)
{
    const std::string* value = h.find(key);
    if (!value) return std::nullopt;
    const auto words = split_words(*value, k_separators);
    if (words.size() != count)
        throw file_error(path, "'" + std::string(key) + "' has " + std::to_string(words.size()) + " values, expected " +
                                   std::to_string(count) + " " + why);
    std::vector<double> out;
    for (const auto w : words) out.push_back(field_double(path, key, w));
    return out;
}

/// The value of the first present key among `aliases`; refuses aliases that disagree.
std::optional<std::vector<double>> aliased_numbers(const std::string& path, const HeaderFields& h,
                                                   std::initializer_list<std::string_view> aliases, std::size_t count,
                                                   const std::string& why)
{
    std::optional<std::vector<double>> found;
    std::string_view found_key;
    for (const auto key : aliases) {
        auto v = numbers(path, h, key, count, why);
        if (!v) continue;
        if (found && *found != *v)
            throw file_error(path, "'" + std::string(found_key) + "' and '" + std::string(key) +
                                       "' both give the same property with different values");
        if (!found) {
            found = std::move(v);
            found_key = key;
        }
    }
    return found;
}

bool parse_bool(const std::string& path, const HeaderFields& h, std::string_view key, bool fallback)
{
    const std::string* value = h.find(key);
    if (!value) return fallback;
    if (*value == "True" || *value == "true" || *value == "TRUE" || *value == "1") return true;
    if (*value == "False" || *value == "false" || *value == "FALSE" || *value == "0") return false;
    throw file_error(path, "'" + std::string(key) + "' is '" + printable(*value) + "', expected True or False");
}

ScalarType element_type(const std::string& path, const std::string& name)
{
    static const std::map<std::string, ScalarType, std::less<>> types = {
        {"MET_UCHAR", ScalarType::u8},  {"MET_CHAR", ScalarType::i8},   {"MET_USHORT", ScalarType::u16},
        {"MET_SHORT", ScalarType::i16}, {"MET_UINT", ScalarType::u32},  {"MET_INT", ScalarType::i32},
        {"MET_FLOAT", ScalarType::f32}, {"MET_DOUBLE", ScalarType::f64}};
    const auto it = types.find(name);
    if (it == types.end())
        throw file_error(path, "unsupported ElementType '" + printable(name) +
                                   "' (expected MET_UCHAR, MET_CHAR, MET_USHORT, MET_SHORT, MET_UINT, MET_INT, "
                                   "MET_FLOAT or MET_DOUBLE)");
    return it->second;
}

std::uint64_t file_size(const std::string& path, const std::string& file)
{
    std::error_code ec;
    const auto size = std::filesystem::file_size(file, ec);
    if (ec) throw file_error(path, "cannot read the size of data file '" + file + "': " + ec.message());
    return size;
}

} // namespace

Volume read_metaimage(const std::string& path)
{
    const HeaderFields h = read_header(path);

    if (const auto* type = h.find("ObjectType"); type && *type != "Image")
        throw file_error(path, "ObjectType is '" + printable(*type) + "', expected Image");
    const std::string* ndims_text = h.find("NDims");
    if (!ndims_text) throw file_error(path, "header has no 'NDims'");
    const std::int64_t ndims = field_int(path, "NDims", *ndims_text);
    if (ndims != 2 && ndims != 3)
        throw file_error(path, "NDims = " + std::to_string(ndims) + ": only 2-D and 3-D images are supported");
    const auto n = static_cast<std::size_t>(ndims);
    const std::string for_ndims = "for NDims " + std::to_string(ndims);

    Volume v;
    v.source = path;
    if (!h.find("DimSize")) throw file_error(path, "header has no 'DimSize'");
    const auto dim_words = split_words(*h.find("DimSize"), k_separators);
    if (dim_words.size() != n)
        throw file_error(path, "'DimSize' has " + std::to_string(dim_words.size()) + " values, expected " +
                                   std::to_string(n) + " " + for_ndims);
    v.dims = {1, 1, 1};
    for (std::size_t a = 0; a < n; ++a) {
        v.dims[a] = field_int(path, "DimSize", dim_words[a]);
        if (v.dims[a] <= 0)
            throw file_error(path, "'DimSize' of axis " + std::to_string(a) + " is " + std::to_string(v.dims[a]) +
                                       " (must be positive)");
    }
    const std::string* type_name = h.find("ElementType");
    if (!type_name) throw file_error(path, "header has no 'ElementType'");
    v.type = element_type(path, *type_name);
    if (const auto* channels = h.find("ElementNumberOfChannels");
        channels && field_int(path, "ElementNumberOfChannels", *channels) != 1)
        throw file_error(path, "ElementNumberOfChannels = " + printable(*channels) +
                                   ": only single-channel (scalar) images are supported");
    if (!parse_bool(path, h, "BinaryData", true))
        throw file_error(path, "BinaryData = False (voxels as text) is not supported");

    // Geometry: ElementSpacing, else ElementSize, else 1 mm.
    auto spacing = numbers(path, h, "ElementSpacing", n, for_ndims);
    if (!spacing) spacing = numbers(path, h, "ElementSize", n, for_ndims);
    if (!spacing) spacing = std::vector<double>(n, 1.0);
    for (std::size_t a = 0; a < n; ++a)
        if (!((*spacing)[a] > 0.0))
            throw file_error(path, "voxel spacing of axis " + std::to_string(a) + " is " + number_text((*spacing)[a]) +
                                       " (must be positive)");
    const auto offset =
        aliased_numbers(path, h, {"Offset", "Origin", "Position"}, n, for_ndims).value_or(std::vector<double>(n, 0.0));
    const auto matrix =
        aliased_numbers(path, h, {"TransformMatrix", "Rotation", "Orientation"}, n * n, "(NDims x NDims) " + for_ndims);
    // Values [a*n .. a*n+n-1] are index axis a's direction: column a (see the top of this file).
    Eigen::Matrix3d direction = Eigen::Matrix3d::Identity();
    Eigen::Vector3d s(1.0, 1.0, 1.0);
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();
    for (Eigen::Index a = 0; a < ndims; ++a) {
        if (matrix)
            for (Eigen::Index r = 0; r < ndims; ++r)
                direction(r, a) = (*matrix)[static_cast<std::size_t>(a * ndims + r)];
        s[a] = (*spacing)[static_cast<std::size_t>(a)];
        origin[a] = offset[static_cast<std::size_t>(a)];
    }
    v.index_to_world = make_index_to_world(s, direction, origin);

    // Where the voxels are.
    const bool element_msb = parse_bool(path, h, "ElementByteOrderMSB", false);
    const bool msb = parse_bool(path, h, "BinaryDataByteOrderMSB", element_msb);
    if (h.find("BinaryDataByteOrderMSB") && h.find("ElementByteOrderMSB") && msb != element_msb)
        throw file_error(path, "'BinaryDataByteOrderMSB' and 'ElementByteOrderMSB' disagree");
    const bool compressed = parse_bool(path, h, "CompressedData", false);
    const std::int64_t header_size = h.find("HeaderSize") ? field_int(path, "HeaderSize", *h.find("HeaderSize")) : 0;
    if (header_size < -1)
        throw file_error(path, "HeaderSize = " + std::to_string(header_size) + " (must be -1 or more)");
    const std::string& data_name = *h.find("ElementDataFile");
    if (data_name.empty()) throw file_error(path, "'ElementDataFile' is empty");
    if (data_name.rfind("LIST", 0) == 0)
        throw file_error(path, "ElementDataFile = LIST (one file per slice) is not supported");
    if (data_name.find('%') != std::string::npos)
        throw file_error(path, "ElementDataFile '" + printable(data_name) +
                                   "' is a numbered pattern (one file per slice), which is not supported");
    const bool local = data_name == "LOCAL" || data_name == "Local" || data_name == "local";
    std::string data_path = path;
    if (!local) {
        const std::filesystem::path name(data_name);
        data_path = (name.is_absolute() ? name : std::filesystem::path(path).parent_path() / name).string();
        std::error_code ec;
        if (std::filesystem::is_directory(data_path, ec))
            throw file_error(path, "data file '" + data_path + "' (ElementDataFile) is a folder, not a file");
        if (!std::filesystem::is_regular_file(data_path, ec))
            throw file_error(path, "data file '" + data_path + "' (ElementDataFile) does not exist");
    }
    const std::string data_what = local ? path : path + " (data file " + data_path + ")";

    std::uint64_t count = 1;
    for (const auto d : v.dims) {
        if (count > std::numeric_limits<std::uint64_t>::max() / static_cast<std::uint64_t>(d))
            throw file_error(path, "DimSize overflows 64-bit sizes");
        count *= static_cast<std::uint64_t>(d);
    }
    check_allocation(path, count, scalar_size(v.type));
    const std::uint64_t bytes = static_cast<std::uint64_t>(v.voxel_count()) * scalar_size(v.type);
    const std::uint64_t size = file_size(path, data_path);
    std::uint64_t start = local ? h.end : 0;
    if (header_size > 0) start = static_cast<std::uint64_t>(header_size);

    if (compressed) {
        std::uint64_t packed = 0;
        if (const auto* text = h.find("CompressedDataSize")) {
            const std::int64_t declared = field_int(path, "CompressedDataSize", *text);
            if (declared <= 0) throw file_error(path, "CompressedDataSize = " + *text + " (must be positive)");
            packed = static_cast<std::uint64_t>(declared);
            if (header_size == -1) start = packed <= size ? size - packed : 0;
        } else if (header_size == -1) {
            throw file_error(path, "HeaderSize = -1 with CompressedData needs CompressedDataSize");
        } else {
            packed = size > start ? size - start : 0;
        }
        if (start > size || size - start < packed)
            throw file_error(data_what, "truncated: the compressed data needs " + std::to_string(packed) +
                                            " bytes from offset " + std::to_string(start) + ", the file has " +
                                            std::to_string(size > start ? size - start : 0));
        check_allocation(data_what, packed, 1);
        std::vector<std::byte> zipped(packed);
        read_file_range(data_path, start, zipped.data(), packed, path);
        v.data = inflate_exact(zipped.data(), zipped.size(), bytes, data_what);
    } else {
        if (header_size == -1) start = size >= bytes ? size - bytes : 0;
        check_voxel_bytes(v, size > start ? size - start : 0, data_what);
        v.data.resize(bytes);
        read_file_range(data_path, start, v.data.data(), bytes, path);
    }
    if (msb != (std::endian::native == std::endian::big)) swap_bytes(v);
    validate(v);
    return v;
}

} // namespace vox::io
