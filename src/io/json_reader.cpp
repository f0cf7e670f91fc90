#include "io/json_reader.hpp"

#include "core/memory_limit.hpp"
#include "io/file_bytes.hpp"
#include "io/text_parsing.hpp"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <iterator>
#include <regex>
#include <set>
#include <type_traits>

namespace vox::io {

using detail::number_text;

namespace {

using nlohmann::json;

constexpr double inf = std::numeric_limits<double>::infinity();

/// Parser callback that refuses a key given twice in one object: nlohmann keeps the last one
/// silently, and a document that sets "dt_s" twice is a mistake, not a choice. It tracks the key
/// path of every open object and array so the message names the duplicate like any other error.
class DuplicateKeyCheck {
public:
    explicit DuplicateKeyCheck(std::string source) : m_source(std::move(source)) {}

    bool operator()(int /*depth*/, json::parse_event_t event, json& parsed)
    {
        switch (event) {
        case json::parse_event_t::object_start:
        case json::parse_event_t::array_start:
            m_frames.push_back({event == json::parse_event_t::array_start, 0, {}, child_path()});
            break;
        case json::parse_event_t::object_end:
        case json::parse_event_t::array_end:
            m_frames.pop_back();
            break;
        case json::parse_event_t::key: {
            Frame& frame = m_frames.back();
            m_key = parsed.get<std::string>();
            if (!frame.keys.insert(m_key).second) {
                throw located_error(m_source, join_key(frame.path, m_key), "key given twice");
            }
            break;
        }
        case json::parse_event_t::value:
            if (!m_frames.empty() && m_frames.back().array) {
                ++m_frames.back().next_index;
            }
            break;
        }
        return true;
    }

private:
    struct Frame {
        bool array = false;
        std::size_t next_index = 0; ///< arrays: index of the next element
        std::set<std::string> keys; ///< objects: keys seen so far
        std::string path;
    };

    /// Path of an object or array that starts now, as an element or member of the open frame.
    std::string child_path()
    {
        if (m_frames.empty()) {
            return {};
        }
        Frame& parent = m_frames.back();
        return parent.array ? join_index(parent.path, parent.next_index++) : join_key(parent.path, m_key);
    }

    std::string m_source;
    std::vector<Frame> m_frames;
    std::string m_key;
};

} // namespace

/// How deep a JSON value may nest (a scene nests four or five levels).
constexpr int k_max_json_depth = 64;
/// How long one string (key or value) may be: a file path is at most 4096 bytes on Linux.
constexpr std::size_t k_max_json_string = 4096;
/// What parsing may cost per byte of text: a parsed value takes 16 bytes and needs at least two
/// characters ("0,"), so 8 bytes per character bounds the document's size in memory.
constexpr std::uint64_t k_parsed_bytes_per_char = 8;

namespace {

/// Refuses a string longer than k_max_json_string before the parser reads it: the parser would hold
/// all of it (a hostile file's 100 MB name) before any callback could look, and messages would
/// quote it. Skips comments as the parser does.
void check_string_lengths(std::string_view text, const std::string& source)
{
    std::size_t line = 1;
    for (std::size_t i = 0; i < text.size(); ++i) {
        const char c = text[i];
        if (c == '\n') {
            ++line;
        } else if (c == '/' && i + 1 < text.size() && text[i + 1] == '/') {
            i = std::min(text.find('\n', i), text.size()) - 1;
        } else if (c == '/' && i + 1 < text.size() && text[i + 1] == '*') {
            const std::size_t end = std::min(text.find("*/", i + 2), text.size());
            line += static_cast<std::size_t>(std::count(text.begin() + static_cast<std::ptrdiff_t>(i),
                                                        text.begin() + static_cast<std::ptrdiff_t>(end), '\n'));
            i = end + 1;
        } else if (c == '"') {
            const std::size_t start = i++;
            while (i < text.size() && text[i] != '"' && text[i] != '\n') i += text[i] == '\\' ? 2 : 1;
            if (i - start - 1 > k_max_json_string)
                throw file_error(source, "line " + std::to_string(line) + ": a string of " + std::to_string(i - start - 1) +
                                             " bytes, more than the " + std::to_string(k_max_json_string) +
                                             " a string may have");
            if (i < text.size() && text[i] == '\n') --i; // the parser will refuse the open string
        }
    }
}

} // namespace

json parse_json(std::string_view text, const std::string& source)
{
    check_allocation(source + " (parsed)", text.size(), k_parsed_bytes_per_char);
    check_string_lengths(text, source);
    try {
        DuplicateKeyCheck check(source);
        return json::parse(
            text,
            [&](int depth, json::parse_event_t event, json& parsed) {
                // A hostile file nests arrays 100,000 deep (gigabytes, minutes): no scene nests deeper than a few levels.
                if (depth > k_max_json_depth)
                    throw file_error(source, "values nested deeper than " + std::to_string(k_max_json_depth) + " levels (the limit)");
                return check(depth, event, parsed);
            },
            /*allow_exceptions=*/true, /*ignore_comments=*/true);
    } catch (const json::out_of_range& e) {
        // nlohmann: "[json.exception.out_of_range.406] number overflow parsing '1e999'"
        const std::string what = e.what();
        const std::size_t quote = what.find('\'');
        throw file_error(source, "a number too large for a double" + (quote == std::string::npos ? std::string() : ": " + what.substr(quote)));
    } catch (const json::parse_error& e) {
        // nlohmann: "[json.exception.parse_error.101] parse error at line 3, column 5: syntax error ..."
        static const std::regex located(R"(line (\d+), column (\d+): (.*))");
        std::smatch m;
        const std::string what = e.what();
        if (std::regex_search(what, m, located)) {
            throw file_error(source, "line " + m[1].str() + " column " + m[2].str() + ": " + m[3].str());
        }
        throw file_error(source, what);
    }
}

json read_json_file(const std::filesystem::path& path)
{
    const std::string source = path.string();
    const std::vector<std::byte> bytes = read_file_bytes(source);
    return parse_json(std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()), source);
}

namespace {

/// Appends `value` as JSON text to `out`, stopping soon after `out` reaches `limit` characters:
/// a hostile document's array of millions of numbers is not written out only to be cut. The same
/// text as nlohmann's dump() up to the cut.
void append_shown(const json& value, std::string& out, std::size_t limit)
{
    if (value.is_array() || value.is_object()) {
        out += value.is_array() ? '[' : '{';
        bool first = true;
        for (const auto& [key, member] : value.items()) {
            if (out.size() > limit) return;
            if (!first) out += ',';
            first = false;
            if (value.is_object()) out += json(key).dump() + ':';
            append_shown(member, out, limit);
        }
        out += value.is_array() ? ']' : '}';
        return;
    }
    out += value.dump();
}

} // namespace

std::string show(const json& value)
{
    constexpr std::size_t max_length = 48;
    std::string text;
    append_shown(value, text, max_length);
    if (text.size() > max_length) {
        text = text.substr(0, max_length - 3) + "...";
    }
    return text;
}

std::string join_key(const std::string& path, std::string_view key)
{
    const bool plain = !key.empty() && std::all_of(key.begin(), key.end(), [](char c) {
        return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
               c == '-';
    });
    if (!plain) {
        return path + "[" + json(std::string(key)).dump() + "]";
    }
    return path.empty() ? std::string(key) : path + "." + std::string(key);
}

std::string join_index(const std::string& path, std::size_t index)
{
    return path + "[" + std::to_string(index) + "]";
}

InputError located_error(const std::string& source, const std::string& path, std::string_view problem)
{
    return file_error(source, path.empty() ? std::string(problem) : path + ": " + std::string(problem));
}

std::string Bound::describe() const
{
    if (hi == inf) {
        return (lo_open ? "> " : ">= ") + number_text(lo);
    }
    return std::string("in ") + (lo_open ? "(" : "[") + number_text(lo) + ", " + number_text(hi) +
           (hi_open ? ")" : "]");
}

Bound greater_than(double lo) { return {lo, inf, true, false}; }
Bound at_least(double lo) { return {lo, inf, false, false}; }
Bound closed_range(double lo, double hi) { return {lo, hi, false, false}; }
Bound open_range(double lo, double hi) { return {lo, hi, true, true}; }

Bound half_open_range(double lo, double hi) { return {lo, hi, true, false}; }

void JsonNode::fail(std::string_view problem) const { throw located_error(m_context->source, m_path, problem); }

void JsonNode::fail_type(std::string_view expected) const
{
    fail("expected " + std::string(expected) + ", got " + show(*m_value));
}

std::vector<JsonNode> JsonNode::elements() const
{
    if (!m_value->is_array()) {
        fail_type("an array");
    }
    std::vector<JsonNode> result;
    for (std::size_t i = 0; i < m_value->size(); ++i) {
        result.emplace_back((*m_value)[i], join_index(m_path, i), *m_context);
    }
    return result;
}

std::vector<std::pair<std::string, JsonNode>> JsonNode::members() const
{
    if (!m_value->is_object()) {
        fail_type("an object");
    }
    std::vector<std::pair<std::string, JsonNode>> result;
    for (const auto& [key, member] : m_value->items()) {
        result.emplace_back(key, JsonNode(member, join_key(m_path, key), *m_context));
    }
    return result;
}

template <class T> T as(const JsonNode& node, const Bound& bound)
{
    const json& v = node.value();
    if constexpr (std::is_same_v<T, double>) {
        if (!v.is_number()) {
            node.fail_type("a number");
        }
        const double x = v.get<double>();
        if (!bound.contains(x)) {
            node.fail("must be " + bound.describe() + ", got " + show(v));
        }
        return x;
    } else if constexpr (std::is_same_v<T, int>) {
        if (!v.is_number_integer()) {
            node.fail_type("an integer");
        }
        const bool fits = v.is_number_unsigned()
                              ? v.get<std::uint64_t>() <= static_cast<std::uint64_t>(std::numeric_limits<T>::max())
                              : v.get<std::int64_t>() >= std::numeric_limits<T>::min() &&
                                    v.get<std::int64_t>() <= std::numeric_limits<T>::max();
        if (!fits) {
            node.fail("integer " + show(v) + " is out of range");
        }
        const T x = static_cast<T>(v.get<std::int64_t>());
        if (!bound.contains(x)) {
            node.fail("must be " + bound.describe() + ", got " + show(v));
        }
        return x;
    } else if constexpr (std::is_same_v<T, bool>) {
        if (!v.is_boolean()) {
            node.fail_type("true or false");
        }
        return v.get<bool>();
    } else if constexpr (std::is_same_v<T, std::string>) {
        if (!v.is_string()) {
            node.fail_type("a string");
        }
        return v.get<std::string>();
    } else if constexpr (std::is_same_v<T, Eigen::Vector3d>) {
        if (!v.is_array() || v.size() != 3) {
            node.fail_type("an array of 3 numbers");
        }
        const std::vector<JsonNode> items = node.elements();
        return Eigen::Vector3d(as<double>(items[0], bound), as<double>(items[1], bound), as<double>(items[2], bound));
    } else {
        static_assert(sizeof(T) == 0, "as<T>: no conversion for this type");
    }
}

// The conversions documents use. Labels are std::int32_t, which is int on every platform we build
// for; a platform where it is not fails to link as<std::int32_t> rather than misreading labels.
template double as<double>(const JsonNode&, const Bound&);
template int as<int>(const JsonNode&, const Bound&);
template std::string as<std::string>(const JsonNode&, const Bound&);
template bool as<bool>(const JsonNode&, const Bound&);
template Eigen::Vector3d as<Eigen::Vector3d>(const JsonNode&, const Bound&);

std::string_view choose(const JsonNode& node, std::initializer_list<std::string_view> names)
{
    const std::string text = as<std::string>(node);
    const auto found = std::find(names.begin(), names.end(), text);
    if (found == names.end()) {
        node.fail("expected one of " + quoted_list(names) + ", got " + show(node.value()));
    }
    return *found;
}

std::filesystem::path resolved_path(const JsonNode& node)
{
    const std::string text = as<std::string>(node);
    if (text.empty()) {
        node.fail("expected a path, got an empty string");
    }
    return (node.context().folder / text).lexically_normal();
}

std::filesystem::path existing_file(const JsonNode& node)
{
    const std::filesystem::path path = resolved_path(node);
    std::error_code error;
    const auto status = std::filesystem::status(path, error);
    if (!std::filesystem::exists(status)) {
        node.fail("file not found: " + path.string());
    }
    if (std::filesystem::is_directory(status)) {
        node.fail("is a folder, not a file: " + path.string());
    }
    return path;
}

JsonReader::JsonReader(const JsonNode& node) : m_node(node)
{
    if (!node.value().is_object()) {
        node.fail_type("an object");
    }
}

bool JsonReader::has(std::string_view key) const { return m_node.value().contains(key); }

JsonNode JsonReader::required_node(std::string_view key)
{
    if (std::optional<JsonNode> node = optional_node(key)) {
        return *node;
    }
    throw located_error(m_node.context().source, join_key(m_node.path(), key), "required key is missing");
}

std::optional<JsonNode> JsonReader::optional_node(std::string_view key)
{
    m_known.emplace_back(key);
    const auto found = m_node.value().find(key);
    if (found == m_node.value().end()) {
        return std::nullopt;
    }
    return JsonNode(*found, join_key(m_node.path(), key), m_node.context());
}

std::string_view JsonReader::exactly_one_of(std::initializer_list<std::string_view> keys) const
{
    std::vector<std::string_view> present;
    std::copy_if(keys.begin(), keys.end(), std::back_inserter(present), [&](std::string_view k) { return has(k); });
    if (present.size() > 1) {
        m_node.fail("takes only one of " + quoted_list(keys) + " (found " + quoted_list(present) + ")");
    }
    if (present.empty()) {
        std::vector<std::string_view> found;
        for (const auto& item : m_node.value().items()) {
            found.push_back(item.key());
        }
        m_node.fail("needs one of " + quoted_list(keys) +
                    (found.empty() ? std::string(", got an empty object") : " (found " + quoted_list(found) + ")"));
    }
    return present.front();
}

void JsonReader::finish(std::string_view what) const
{
    for (const auto& [key, value] : m_node.value().items()) {
        if (std::find(m_known.begin(), m_known.end(), key) != m_known.end()) {
            continue;
        }
        std::string known;
        for (const std::string& k : m_known) {
            known += (known.empty() ? "" : ", ") + k;
        }
        const std::string qualifier = what.empty() ? "" : " " + std::string(what);
        throw located_error(m_node.context().source, join_key(m_node.path(), key),
                            "unknown key" + qualifier + " (known keys: " + known + ")");
    }
}

} // namespace vox::io
