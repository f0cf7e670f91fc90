#include "io/text_parsing.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <system_error>

namespace vox::io::detail {
namespace {

/// The whole of `s` as a T; nullopt when `s` is empty, has anything after the number, or is out of
/// T's range.
template <class T> std::optional<T> whole_number(std::string_view s)
{
    T v{};
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc() || end != s.data() + s.size() || s.empty()) return std::nullopt;
    return v;
}

/// `s` without one leading '+', which from_chars rejects.
std::string_view without_plus(std::string_view s)
{
    if (!s.empty() && s.front() == '+') s.remove_prefix(1);
    return s;
}

} // namespace

std::string_view trim(std::string_view s)
{
    const auto first = s.find_first_not_of(" \t\r");
    if (first == std::string_view::npos) return {};
    const auto last = s.find_last_not_of(" \t\r");
    return s.substr(first, last - first + 1);
}

std::vector<std::string_view> split_words(std::string_view s, std::string_view separators)
{
    std::vector<std::string_view> words;
    std::size_t pos = 0;
    while ((pos = s.find_first_not_of(separators, pos)) != std::string_view::npos) {
        const auto end = std::min(s.find_first_of(separators, pos), s.size());
        words.push_back(s.substr(pos, end - pos));
        pos = end;
    }
    return words;
}

std::optional<double> parse_double(std::string_view s) { return whole_number<double>(without_plus(s)); }

std::optional<long long> parse_integer(std::string_view s) { return whole_number<long long>(s); }

double field_double(const std::string& path, std::string_view field, std::string_view word, bool allow_nan)
{
    word = without_plus(word);
    const std::optional<double> v = whole_number<double>(word);
    if (!v) throw file_error(path, "'" + std::string(field) + "' value '" + printable(word) + "' is not a number");
    if (!std::isfinite(*v) && !(allow_nan && std::isnan(*v)))
        throw file_error(path, "'" + std::string(field) + "' value '" + printable(word) + "' is not finite");
    return *v;
}

std::int64_t field_int(const std::string& path, std::string_view field, std::string_view word)
{
    const std::optional<std::int64_t> v = whole_number<std::int64_t>(word);
    if (!v) throw file_error(path, "'" + std::string(field) + "' value '" + printable(word) + "' is not an integer");
    return *v;
}

std::string printable(std::string_view s)
{
    std::string out;
    for (const char c : s.substr(0, 60)) out += (c >= 32 && c < 127) ? c : '?';
    if (s.size() > 60) out += "...";
    return out;
}

bool is_binary(std::string_view s)
{
    return std::any_of(s.begin(), s.end(), [](char c) {
        const auto u = static_cast<unsigned char>(c);
        return (u < 32 && k_white_space.find(c) == std::string_view::npos) || u == 127;
    });
}

std::string number_text(double v)
{
    std::array<char, 32> buffer{};
    const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), v);
    return std::string(buffer.data(), result.ptr);
}

std::string lower_case(std::string s)
{
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return s;
}

std::string lower_extension(const std::string& path)
{
    const auto slash = path.find_last_of('/');
    const auto dot = path.find_last_of('.');
    if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
    return lower_case(path.substr(dot));
}

} // namespace vox::io::detail
