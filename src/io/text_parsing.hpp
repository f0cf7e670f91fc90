#pragma once
// Internal to src/io: text parsing shared by the readers of text formats and text headers (OFF,
// OBJ, PLY, STL ascii, MetaImage, NRRD): words, numbers, the fields of a "key = value" header, and
// short texts for error messages.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace vox::io::detail {

/// The white space characters of the C locale: blank, tab, carriage return, newline, vertical tab,
/// form feed.
inline constexpr std::string_view k_white_space = " \t\r\n\v\f";

/// `s` without leading and trailing blanks, tabs and carriage returns.
[[nodiscard]] std::string_view trim(std::string_view s);

/// The runs of characters not in `separators` in `s`, in order.
[[nodiscard]] std::vector<std::string_view> split_words(std::string_view s,
                                                        std::string_view separators = k_white_space);

/// The whole of `s` as a number ("1", "-2.5e3", "+4", "nan", "inf"); nullopt for anything else.
[[nodiscard]] std::optional<double> parse_double(std::string_view s);

/// The whole of `s` as an integer ("12", "-3"; no leading '+'); nullopt for anything else,
/// including values outside long long.
[[nodiscard]] std::optional<long long> parse_integer(std::string_view s);

/// The value `word` of header field `field` as a finite number (a leading '+' is allowed; so is
/// "nan" when `allow_nan`). Throws InputError "PATH: 'FIELD' value 'WORD' is not a number" or
/// "... is not finite".
[[nodiscard]] double field_double(const std::string& path, std::string_view field, std::string_view word,
                                  bool allow_nan = false);

/// The value `word` of header field `field` as an integer (no leading '+'). Throws InputError
/// "PATH: 'FIELD' value 'WORD' is not an integer".
[[nodiscard]] std::int64_t field_int(const std::string& path, std::string_view field, std::string_view word);

/// At most the first 60 characters of `s`, anything outside printable ASCII shown as '?' and "..."
/// after a cut: file text safe to quote in a one-line message.
[[nodiscard]] std::string printable(std::string_view s);

/// True when `s` holds a control byte other than white space (NUL, ESC, ...): binary data, not
/// text. Messages then say so instead of quoting it.
[[nodiscard]] bool is_binary(std::string_view s);

/// Shortest text that reads back as `v` ("0.5", "30000", "1e-06", "-1").
[[nodiscard]] std::string number_text(double v);

/// `s` in lower case (ASCII).
[[nodiscard]] std::string lower_case(std::string s);
/// The last extension of `path` in lower case, with its dot (".nii" for "A.NII"), or "".
[[nodiscard]] std::string lower_extension(const std::string& path);

/// The fields of a text header by key, and the byte offset just past the header in its file.
struct HeaderFields {
    std::map<std::string, std::string, std::less<>> fields;
    std::map<std::string, std::string> pairs; ///< NRRD's free-form "key:=value" lines, as written
    std::uint64_t end = 0;

    /// The value of `key`; nullptr when the header does not have it.
    [[nodiscard]] const std::string* find(std::string_view key) const
    {
        const auto it = fields.find(key);
        return it == fields.end() ? nullptr : &it->second;
    }
};

} // namespace vox::io::detail
