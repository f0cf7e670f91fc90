#pragma once
// The strict JSON reader every JSON format of the project uses: scene files now (io/scene.hpp),
// later statistics and recordings. A format's schema is code that walks the document: a JsonNode
// is a JSON value with its key path; a JsonReader walks one JSON object, remembers which keys were
// asked for, and refuses the rest in finish(). Adding a key to a format is one
// `reader.optional(...)` or `reader.required<T>(...)` line.
//
// Every error is an InputError "SOURCE: key.path: problem": SOURCE names the document (its file),
// key paths join names with dots and count array elements from 0 ("tools[1].name"); a key that is
// not a plain name is quoted (`solver["dt s"]`).

#include "core/error.hpp"

#include <Eigen/Core>
#include <nlohmann/json_fwd.hpp>

#include <algorithm>
#include <array>
#include <cstddef>
#include <filesystem>
#include <initializer_list>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace vox::io {

/// Parses a JSON document. Comments (// and /* */) are allowed; a key given twice in one object is
/// refused, since nlohmann would silently keep the last one. `source` names the document in
/// messages. Throws InputError "SOURCE: key.path: key given twice", or "SOURCE: line L column C:
/// problem" for text that is not JSON.
/// Refused too: strings longer than 4096 bytes, values nested deeper than 64 levels, and text whose
/// parsed form could pass the memory limit (8 bytes per character).
[[nodiscard]] nlohmann::json parse_json(std::string_view text, const std::string& source);

/// Reads a JSON file (plain or gzip) and parses it with parse_json; messages start with the path
/// as given. Throws InputError also when the file is missing or unreadable.
[[nodiscard]] nlohmann::json read_json_file(const std::filesystem::path& path);

/// A value as the user wrote it, shortened so one message stays one readable line.
[[nodiscard]] std::string show(const nlohmann::json& value);

/// `path.key`, or `key` at the top level. Keys made of letters, digits, '_' and '-' print plain;
/// any other key prints quoted, `path["odd key"]`, so the path stays unambiguous.
[[nodiscard]] std::string join_key(const std::string& path, std::string_view key);

/// `path[index]`.
[[nodiscard]] std::string join_index(const std::string& path, std::size_t index);

/// "SOURCE: key.path: problem", or "SOURCE: problem" when `path` is empty (the top level).
[[nodiscard]] InputError located_error(const std::string& source, const std::string& path,
                                       std::string_view problem);

/// `"a", "b", "c"`, for messages listing the accepted names.
template <class Names> [[nodiscard]] std::string quoted_list(const Names& names)
{
    std::string list;
    for (const std::string_view name : names) {
        list += (list.empty() ? "\"" : ", \"") + std::string(name) + "\"";
    }
    return list;
}

/// What every node of one document shares: the document's name for messages, and the absolute
/// folder its relative paths resolve against.
struct JsonContext {
    std::string source;
    std::filesystem::path folder;
};

/// An allowed interval for numbers (each component of a vector); the default allows any number.
struct Bound {
    double lo = -std::numeric_limits<double>::infinity();
    double hi = std::numeric_limits<double>::infinity();
    bool lo_open = false;
    bool hi_open = false;

    [[nodiscard]] bool contains(double v) const
    {
        return (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);
    }
    /// "> 0", ">= 1", "in [0, 6]", "in (-1, 0.5)": completes "must be ...".
    [[nodiscard]] std::string describe() const;
};

/// (lo, infinity).
[[nodiscard]] Bound greater_than(double lo);
/// [lo, infinity).
[[nodiscard]] Bound at_least(double lo);
/// [lo, hi].
[[nodiscard]] Bound closed_range(double lo, double hi);
/// (lo, hi).
[[nodiscard]] Bound open_range(double lo, double hi);
/// (lo, hi].
[[nodiscard]] Bound half_open_range(double lo, double hi);

/// A JSON value and its key path in the document. Non-owning: the value and the context must
/// outlive the node.
class JsonNode {
public:
    JsonNode(const nlohmann::json& value, std::string path, const JsonContext& context)
        : m_value(&value), m_path(std::move(path)), m_context(&context)
    {
    }

    [[nodiscard]] const nlohmann::json& value() const { return *m_value; }
    /// The key path, empty for the document itself.
    [[nodiscard]] const std::string& path() const { return m_path; }
    [[nodiscard]] const JsonContext& context() const { return *m_context; }

    /// Throws InputError "SOURCE: PATH: problem".
    [[noreturn]] void fail(std::string_view problem) const;
    /// Throws InputError "SOURCE: PATH: expected EXPECTED, got VALUE".
    [[noreturn]] void fail_type(std::string_view expected) const;

    /// The elements of an array, each with its indexed path; fails unless the value is an array.
    [[nodiscard]] std::vector<JsonNode> elements() const;

    /// The members of an object whose keys are data (label numbers), not schema keys; fails unless
    /// the value is an object.
    [[nodiscard]] std::vector<std::pair<std::string, JsonNode>> members() const;

private:
    const nlohmann::json* m_value;
    std::string m_path;
    const JsonContext* m_context;
};

/// Converts a node to T, checking its JSON type and, for numbers, the bound. Defined for double,
/// int (also std::int32_t), std::string and Eigen::Vector3d (an array of 3 numbers, each checked
/// against the bound).
template <class T> [[nodiscard]] T as(const JsonNode& node, const Bound& bound = {});

/// A string naming one of `names`; returns the name (a view of the caller's literal).
[[nodiscard]] std::string_view choose(const JsonNode& node, std::initializer_list<std::string_view> names);

/// A non-empty string naming a path, resolved against the context's folder, absolute.
[[nodiscard]] std::filesystem::path resolved_path(const JsonNode& node);

/// A path (see resolved_path) to a file that exists now, so a document naming a missing input is
/// refused before any work starts.
[[nodiscard]] std::filesystem::path existing_file(const JsonNode& node);

/// Walks one JSON object. Every key the schema knows is asked for (required or optional) before
/// finish(), which refuses the keys that never were.
class JsonReader {
public:
    /// Fails unless the node is an object.
    explicit JsonReader(const JsonNode& node);

    [[nodiscard]] const JsonNode& node() const { return m_node; }

    /// Whether the key is present; does not make it a known key.
    [[nodiscard]] bool has(std::string_view key) const;

    /// The key's node; missing is an error.
    [[nodiscard]] JsonNode required_node(std::string_view key);

    /// The key's node when present.
    [[nodiscard]] std::optional<JsonNode> optional_node(std::string_view key);

    template <class T> [[nodiscard]] T required(std::string_view key, const Bound& bound = {})
    {
        return as<T>(required_node(key), bound);
    }

    template <class T> [[nodiscard]] T optional(std::string_view key, T fallback, const Bound& bound = {})
    {
        const std::optional<JsonNode> node = optional_node(key);
        return node ? as<T>(*node, bound) : fallback;
    }

    /// Exactly one of `keys` must be present (e.g. the object's source); returns it.
    [[nodiscard]] std::string_view exactly_one_of(std::initializer_list<std::string_view> keys) const;

    /// Refuses every key that was never asked for. `what` says which kind of object this is
    /// ("for a beam phantom") when the allowed keys depend on it.
    void finish(std::string_view what = {}) const;

private:
    JsonNode m_node;
    std::vector<std::string> m_known;
};

/// The names of an enum's values as written in documents.
template <class E, std::size_t N> using NameTable = std::array<std::pair<std::string_view, E>, N>;

/// A string naming one of the table's values; returns that value.
template <class E, std::size_t N> [[nodiscard]] E choose_enum(const JsonNode& node, const NameTable<E, N>& table)
{
    const std::string text = as<std::string>(node);
    for (const auto& [name, value] : table) {
        if (name == text) {
            return value;
        }
    }
    std::array<std::string_view, N> names;
    std::transform(table.begin(), table.end(), names.begin(), [](const auto& entry) { return entry.first; });
    node.fail("expected one of " + quoted_list(names) + ", got " + show(node.value()));
}

} // namespace vox::io
