// INRIMAGE-4 reader. The header is text: "#INRIMAGE-4#{" then KEY=value lines, padded with newlines
// to a multiple of 256 bytes (usually exactly 256, but not always), ending with the line "##}".

#include "core/error.hpp"
#include "core/memory_limit.hpp"
#include "io/file_bytes.hpp"
#include "io/text_parsing.hpp"
#include "io/volume_reader.hpp"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <sstream>

namespace vox::io {

using detail::printable;

namespace {

constexpr std::string_view k_magic = "#INRIMAGE-4#{";
constexpr std::string_view k_end = "##}\n";
constexpr std::size_t k_max_header = 1 << 16;

long long parse_int(const std::string& path, const std::map<std::string, std::string>& kv, const std::string& key,
                    long long fallback, bool required)
{
    const auto it = kv.find(key);
    if (it == kv.end()) {
        if (required) throw file_error(path, "header has no " + key);
        return fallback;
    }
    char* end = nullptr;
    errno = 0;
    const long long v = std::strtoll(it->second.c_str(), &end, 10);
    if (end == it->second.c_str() || *end != '\0')
        throw file_error(path, key + "=" + printable(it->second) + " is not an integer");
    if (errno == ERANGE) throw file_error(path, key + "=" + printable(it->second) + " is beyond a 64-bit integer");
    return v;
}

double parse_real(const std::string& path, const std::map<std::string, std::string>& kv, const std::string& key,
                  double fallback)
{
    const auto it = kv.find(key);
    if (it == kv.end()) return fallback;
    char* end = nullptr;
    const double v = std::strtod(it->second.c_str(), &end);
    if (end == it->second.c_str() || *end != '\0' || !std::isfinite(v))
        throw file_error(path, key + "=" + printable(it->second) + " is not a finite number");
    return v;
}

ScalarType parse_type(const std::string& path, const std::string& type, long long bits)
{
    if (type == "unsigned fixed") {
        if (bits == 8) return ScalarType::u8;
        if (bits == 16) return ScalarType::u16;
        if (bits == 32) return ScalarType::u32;
    } else if (type == "signed fixed") {
        if (bits == 8) return ScalarType::i8;
        if (bits == 16) return ScalarType::i16;
        if (bits == 32) return ScalarType::i32;
    } else if (type == "float") {
        if (bits == 32) return ScalarType::f32;
        if (bits == 64) return ScalarType::f64;
    } else {
        throw file_error(path,
                         "unsupported TYPE=" + printable(type) + " (expected unsigned fixed, signed fixed or float)");
    }
    throw file_error(path, "unsupported PIXSIZE of " + std::to_string(bits) + " bits for TYPE=" + printable(type));
}

bool big_endian_cpu(const std::string& path, const std::string& cpu)
{
    if (cpu.empty() || cpu == "decm" || cpu == "alpha" || cpu == "pc") return false;
    if (cpu == "sun" || cpu == "sgi") return true;
    throw file_error(path, "unknown CPU=" + printable(cpu) + " (expected decm, alpha, pc, sun or sgi)");
}

} // namespace

Volume read_inr(const std::string& path)
{
    const std::vector<std::byte> bytes = read_file_bytes(path);
    const std::string_view text(reinterpret_cast<const char*>(bytes.data()), std::min(bytes.size(), k_max_header));
    if (text.substr(0, k_magic.size()) != k_magic) throw file_error(path, "not an INRIMAGE-4 file (wrong magic)");
    const std::size_t end = text.find(k_end);
    if (end == std::string_view::npos) throw file_error(path, "header has no closing \"##}\" line (truncated?)");
    const std::size_t header_size = end + k_end.size();

    std::map<std::string, std::string> kv;
    std::istringstream lines{std::string(text.substr(k_magic.size(), end - k_magic.size()))};
    for (std::string line; std::getline(lines, line);) {
        if (line.empty() || line[0] == '#') continue;
        const auto eq = line.find('=');
        if (eq == std::string::npos) throw file_error(path, "header line \"" + printable(line) + "\" has no '='");
        kv[line.substr(0, eq)] = line.substr(eq + 1);
    }

    Volume v;
    v.source = path;
    v.dims = {parse_int(path, kv, "XDIM", 0, true), parse_int(path, kv, "YDIM", 0, true),
              parse_int(path, kv, "ZDIM", 1, false)};
    for (int a = 0; a < 3; ++a)
        if (v.dims[a] <= 0)
            throw file_error(path, std::string(1, "XYZ"[a]) + "DIM=" + std::to_string(v.dims[a]) + " is not positive");
    if (parse_int(path, kv, "VDIM", 1, false) != 1)
        throw file_error(path, "VDIM=" + printable(kv["VDIM"]) + ": only scalar images (VDIM=1) are supported");
    std::string bits_text = kv.count("PIXSIZE") ? kv["PIXSIZE"] : "8 bits";
    const long long bits = std::strtoll(bits_text.c_str(), nullptr, 10);
    v.type = parse_type(path, kv.count("TYPE") ? kv["TYPE"] : "unsigned fixed", bits);

    const Eigen::Vector3d spacing(parse_real(path, kv, "VX", 1.0), parse_real(path, kv, "VY", 1.0),
                                  parse_real(path, kv, "VZ", 1.0));
    for (int a = 0; a < 3; ++a)
        if (!(spacing[a] > 0.0))
            throw file_error(path, std::string("V") + "XYZ"[a] + "=" + std::to_string(spacing[a]) +
                                       " is not a positive voxel size");
    // Origins are written as XO/YO/ZO by Inrimage tools and TX/TY/TZ by CGAL.
    const Eigen::Vector3d origin(parse_real(path, kv, "XO", parse_real(path, kv, "TX", 0.0)),
                                 parse_real(path, kv, "YO", parse_real(path, kv, "TY", 0.0)),
                                 parse_real(path, kv, "ZO", parse_real(path, kv, "TZ", 0.0)));
    v.index_to_world = make_index_to_world(spacing, Eigen::Matrix3d::Identity(), origin);

    // The product checked before it is formed: three 64-bit sizes overflow it (found by fuzzing).
    std::uint64_t count = 1;
    for (const std::int64_t d : v.dims) {
        if (count > std::numeric_limits<std::uint64_t>::max() / static_cast<std::uint64_t>(d))
            throw file_error(path, "dimensions overflow 64-bit sizes");
        count *= static_cast<std::uint64_t>(d);
    }
    check_allocation(path, count, scalar_size(v.type));
    const std::size_t need = count * scalar_size(v.type);
    if (bytes.size() - header_size < need)
        throw file_error(path, "truncated: holds " + std::to_string(bytes.size() - header_size) +
                                   " bytes of voxels, the header needs " + std::to_string(need));
    v.data.assign(bytes.begin() + static_cast<std::ptrdiff_t>(header_size),
                  bytes.begin() + static_cast<std::ptrdiff_t>(header_size + need));
    if (big_endian_cpu(path, kv.count("CPU") ? kv["CPU"] : "")) swap_bytes(v);
    validate(v);
    return v;
}

} // namespace vox::io
