#include "io/scene.hpp"

#include "io/file_bytes.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <limits>
#include <optional>
#include <regex>
#include <set>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

namespace vox::io {

namespace {

using nlohmann::json;

// ---------------------------------------------------------------------------------------------
// Schema-walking helpers. A Node is a JSON value with its key path; a Reader walks one JSON
// object, remembers which keys were asked for, and refuses the rest in finish(). Adding a key to
// the format is one `reader.optional(...)` or `reader.required<T>(...)` line.
// ---------------------------------------------------------------------------------------------

/// Shortest text that reads back as `v` ("0.5", "30000", "1e-06").
std::string number_text(double v)
{
    std::array<char, 32> buffer{};
    const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), v);
    return std::string(buffer.data(), result.ptr);
}

/// A value as the user wrote it, shortened so one message stays one readable line.
std::string show(const json& value)
{
    constexpr std::size_t max_length = 48;
    std::string text = value.dump();
    if (text.size() > max_length) {
        text = text.substr(0, max_length - 3) + "...";
    }
    return text;
}

/// Keys made of letters, digits, '_' and '-' print as `a.b`; any other key prints quoted,
/// `a["odd key"]`, so the path stays unambiguous.
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

/// "FILE: key.path: problem", or "FILE: problem" at the top level.
InputError located_error(const std::string& source, const std::string& path, std::string_view problem)
{
    return file_error(source, path.empty() ? std::string(problem) : path + ": " + std::string(problem));
}

/// What every node needs to report errors and resolve paths.
struct Context {
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
    [[nodiscard]] std::string describe() const
    {
        if (hi == std::numeric_limits<double>::infinity()) {
            return (lo_open ? "> " : ">= ") + number_text(lo);
        }
        return std::string("in ") + (lo_open ? "(" : "[") + number_text(lo) + ", " + number_text(hi) +
               (hi_open ? ")" : "]");
    }
};

constexpr double inf = std::numeric_limits<double>::infinity();
Bound greater_than(double lo) { return {lo, inf, true, false}; }
Bound at_least(double lo) { return {lo, inf, false, false}; }
Bound closed_range(double lo, double hi) { return {lo, hi, false, false}; }
Bound open_range(double lo, double hi) { return {lo, hi, true, true}; }

class Node {
public:
    Node(const json& value, std::string path, const Context& context)
        : m_value(&value), m_path(std::move(path)), m_context(&context)
    {
    }

    [[nodiscard]] const json& value() const { return *m_value; }
    [[nodiscard]] const std::string& path() const { return m_path; }
    [[nodiscard]] const Context& context() const { return *m_context; }

    [[noreturn]] void fail(std::string_view problem) const { throw located_error(m_context->source, m_path, problem); }
    [[noreturn]] void fail_type(std::string_view expected) const
    {
        fail("expected " + std::string(expected) + ", got " + show(*m_value));
    }

    /// The elements of an array, each with its indexed path.
    [[nodiscard]] std::vector<Node> elements() const
    {
        if (!m_value->is_array()) {
            fail_type("an array");
        }
        std::vector<Node> result;
        for (std::size_t i = 0; i < m_value->size(); ++i) {
            result.emplace_back((*m_value)[i], join_index(m_path, i), *m_context);
        }
        return result;
    }

    /// The members of an object whose keys are data (label numbers), not schema keys.
    [[nodiscard]] std::vector<std::pair<std::string, Node>> members() const
    {
        if (!m_value->is_object()) {
            fail_type("an object");
        }
        std::vector<std::pair<std::string, Node>> result;
        for (const auto& [key, member] : m_value->items()) {
            result.emplace_back(key, Node(member, join_key(m_path, key), *m_context));
        }
        return result;
    }

private:
    const json* m_value;
    std::string m_path;
    const Context* m_context;
};

/// Converts a node to T, checking its JSON type and, for numbers, the bound.
template <class T> T as(const Node& node, const Bound& bound = {})
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
    } else if constexpr (std::is_same_v<T, int> || std::is_same_v<T, std::int32_t>) {
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
    } else if constexpr (std::is_same_v<T, std::string>) {
        if (!v.is_string()) {
            node.fail_type("a string");
        }
        return v.get<std::string>();
    } else if constexpr (std::is_same_v<T, Eigen::Vector3d>) {
        if (!v.is_array() || v.size() != 3) {
            node.fail_type("an array of 3 numbers");
        }
        const std::vector<Node> items = node.elements();
        return Eigen::Vector3d(as<double>(items[0], bound), as<double>(items[1], bound), as<double>(items[2], bound));
    } else {
        static_assert(sizeof(T) == 0, "as<T>: no conversion for this type");
    }
}

/// `"a", "b", "c"`, for messages listing the accepted names.
template <class Names> std::string quoted_list(const Names& names)
{
    std::string list;
    for (const std::string_view name : names) {
        list += (list.empty() ? "\"" : ", \"") + std::string(name) + "\"";
    }
    return list;
}

/// A string naming one of `names`; returns the name (a view of the caller's literal).
std::string_view choose(const Node& node, std::initializer_list<std::string_view> names)
{
    const std::string text = as<std::string>(node);
    const auto found = std::find(names.begin(), names.end(), text);
    if (found == names.end()) {
        node.fail("expected one of " + quoted_list(names) + ", got " + show(node.value()));
    }
    return *found;
}

/// A non-empty string naming a path, resolved against the scene's folder, absolute.
std::filesystem::path resolved_path(const Node& node)
{
    const std::string text = as<std::string>(node);
    if (text.empty()) {
        node.fail("expected a path, got an empty string");
    }
    return (node.context().folder / text).lexically_normal();
}

/// A path to a file that must exist now (the scene is refused before any work starts).
std::filesystem::path existing_file(const Node& node)
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

class Reader {
public:
    explicit Reader(const Node& node) : m_node(node)
    {
        if (!node.value().is_object()) {
            node.fail_type("an object");
        }
    }

    [[nodiscard]] const Node& node() const { return m_node; }

    /// Whether the key is present; does not make it a known key.
    [[nodiscard]] bool has(std::string_view key) const { return m_node.value().contains(key); }

    /// The key's node; missing is an error.
    [[nodiscard]] Node required_node(std::string_view key)
    {
        if (std::optional<Node> node = optional_node(key)) {
            return *node;
        }
        throw located_error(m_node.context().source, join_key(m_node.path(), key), "required key is missing");
    }

    /// The key's node when present.
    [[nodiscard]] std::optional<Node> optional_node(std::string_view key)
    {
        m_known.emplace_back(key);
        const auto found = m_node.value().find(key);
        if (found == m_node.value().end()) {
            return std::nullopt;
        }
        return Node(*found, join_key(m_node.path(), key), m_node.context());
    }

    template <class T> [[nodiscard]] T required(std::string_view key, const Bound& bound = {})
    {
        return as<T>(required_node(key), bound);
    }

    template <class T> [[nodiscard]] T optional(std::string_view key, T fallback, const Bound& bound = {})
    {
        const std::optional<Node> node = optional_node(key);
        return node ? as<T>(*node, bound) : fallback;
    }

    /// Exactly one of `keys` must be present (e.g. the object's source); returns it.
    [[nodiscard]] std::string_view exactly_one_of(std::initializer_list<std::string_view> keys) const
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

    /// Refuses every key that was never asked for. `what` says which kind of object this is
    /// ("for a beam phantom") when the allowed keys depend on it.
    void finish(std::string_view what = {}) const
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

private:
    Node m_node;
    std::vector<std::string> m_known;
};

template <class E, std::size_t N> using NameTable = std::array<std::pair<std::string_view, E>, N>;

template <class E, std::size_t N> E choose_enum(const Node& node, const NameTable<E, N>& table)
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

constexpr NameTable<SolverType, 2> solver_types{{{"dbg", SolverType::dbg}, {"isxfem", SolverType::isxfem}}};
constexpr NameTable<ConstraintType, 2> constraint_types{
    {{"fixed", ConstraintType::fixed}, {"slide", ConstraintType::slide}}};
constexpr NameTable<ToolShape, 4> tool_shapes{{{"blade", ToolShape::blade},
                                               {"scalpel", ToolShape::scalpel},
                                               {"sphere", ToolShape::sphere},
                                               {"mesh", ToolShape::mesh}}};

// ---------------------------------------------------------------------------------------------
// The sections of a scene.
// ---------------------------------------------------------------------------------------------

const Bound positive = greater_than(0.0);

/// A scalpel's size when the scene gives none: about a No. 10 surgical blade, mm.
const Eigen::Vector3d default_scalpel_size_mm(30.0, 0.5, 8.0);

Selection read_selection(Reader r)
{
    Selection s;
    if (r.exactly_one_of({"label", "threshold"}) == "label") {
        const Node node = r.required_node("label");
        // A single label may be written without brackets.
        const std::vector<Node> items = node.value().is_number() ? std::vector<Node>{node} : node.elements();
        if (items.empty()) {
            node.fail("must list at least one label");
        }
        for (const Node& item : items) {
            const auto label = as<std::int32_t>(item);
            if (std::find(s.labels.begin(), s.labels.end(), label) != s.labels.end()) {
                item.fail("label " + std::to_string(label) + " is listed twice");
            }
            s.labels.push_back(label);
        }
    } else {
        const Node node = r.required_node("threshold");
        if (node.value().is_number()) {
            s.threshold_min = as<double>(node);
        } else {
            if (!node.value().is_array() || node.value().size() != 2) {
                node.fail_type("a number or an array [lo, hi] of 2 numbers");
            }
            const std::vector<Node> bounds = node.elements();
            const double lo = as<double>(bounds[0]);
            const double hi = as<double>(bounds[1]);
            if (lo > hi) {
                node.fail("lower bound " + number_text(lo) + " is above upper bound " + number_text(hi));
            }
            s.threshold_min = lo;
            s.threshold_max = hi;
        }
    }
    r.finish();
    return s;
}

grid::PhantomSpec read_phantom(Reader r)
{
    const Node shape = r.required_node("shape");
    const std::string_view name = choose(shape, {"beam", "block", "sphere", "cylinder", "utube"});
    grid::PhantomSpec p = grid::default_phantom(grid::parse_phantom_shape(std::string(name)));
    const std::optional<Node> voxel = r.optional_node("voxel_mm");
    if (voxel) {
        p.voxel_mm = as<double>(*voxel, positive);
    }

    // The phantom generator needs every size to be a whole number of voxels (docs/phantoms.md);
    // checking here names the key. A size the file gives is named itself; a default size that
    // does not fit the given voxel_mm is reported on voxel_mm.
    struct Extent {
        std::optional<Node> node;
        double mm;
        std::string name;
        bool diameter; ///< mm is twice the key's value
    };
    std::vector<Extent> extents;
    const auto length = [&](std::string_view key, double& field, bool diameter) {
        const std::optional<Node> node = r.optional_node(key);
        if (node) {
            field = as<double>(*node, positive);
        }
        extents.push_back({node, diameter ? 2.0 * field : field, std::string(key), diameter});
    };
    switch (p.shape) {
    case grid::PhantomShape::beam:
    case grid::PhantomShape::block: {
        const std::optional<Node> node = r.optional_node("size_mm");
        if (node) {
            p.size_mm = as<Eigen::Vector3d>(*node, positive);
        }
        for (std::size_t axis = 0; axis < 3; ++axis) {
            extents.push_back({node ? std::optional<Node>(node->elements()[axis]) : std::nullopt,
                               p.size_mm[static_cast<Eigen::Index>(axis)], join_index("size_mm", axis), false});
        }
        break;
    }
    case grid::PhantomShape::sphere:
        length("radius_mm", p.radius_mm, true);
        break;
    case grid::PhantomShape::cylinder:
        length("radius_mm", p.radius_mm, true);
        length("length_mm", p.length_mm, false);
        break;
    case grid::PhantomShape::utube:
        length("leg_mm", p.leg_mm, false);
        length("gap_mm", p.gap_mm, false);
        length("height_mm", p.height_mm, false);
        length("depth_mm", p.depth_mm, false);
        break;
    }
    for (const Extent& e : extents) {
        const double voxels = std::round(e.mm / p.voxel_mm);
        if (voxels >= 1.0 && std::abs(voxels * p.voxel_mm - e.mm) <= 1e-6 * e.mm) {
            continue;
        }
        const std::string extent = (e.diameter ? "the diameter " : "") + number_text(e.mm) + " mm";
        const std::string voxel_text = " is not a whole number of " + number_text(p.voxel_mm) + " mm voxels";
        if (e.node) {
            e.node->fail(extent + voxel_text);
        }
        // Only a given voxel_mm can misfit a default size (every default is a whole number of mm).
        (voxel ? *voxel : r.node()).fail("the default " + e.name + " gives " + extent + ", which" + voxel_text);
    }
    if (p.shape == grid::PhantomShape::utube && p.height_mm <= p.leg_mm) {
        (r.has("height_mm") ? r.required_node("height_mm") : r.required_node("leg_mm"))
            .fail("a utube's height_mm must exceed its leg_mm (the base thickness)");
    }
    r.finish("for a " + std::string(name) + " phantom");
    return p;
}

SceneObject read_object(Reader r)
{
    SceneObject o;
    const std::string_view kind = r.exactly_one_of({"volume", "phantom", "mesh"});
    if (kind == "volume") {
        o.kind = ObjectKind::volume;
        o.file = existing_file(r.required_node("volume"));
        if (const std::optional<Node> select = r.optional_node("select")) {
            o.select = read_selection(Reader(*select));
        }
    } else if (kind == "phantom") {
        o.kind = ObjectKind::phantom;
        o.phantom = read_phantom(Reader(r.required_node("phantom")));
    } else {
        o.kind = ObjectKind::mesh;
        o.file = existing_file(r.required_node("mesh"));
        if (const std::optional<Node> voxel = r.optional_node("voxel_mm")) {
            o.voxel_mm = as<double>(*voxel, positive);
        }
        o.scale_mm_per_unit = r.optional("scale_mm_per_unit", o.scale_mm_per_unit, positive);
    }
    o.levels = r.required<int>("levels", closed_range(0, 6));
    r.finish("for a " + std::string(kind) + " object");
    return o;
}

/// Keys absent from the file keep their values in `m`.
Material read_material(Reader r, Material m)
{
    m.youngs_modulus_pa = r.optional("youngs_modulus_pa", m.youngs_modulus_pa, positive);
    m.poisson_ratio = r.optional("poisson_ratio", m.poisson_ratio, open_range(-1.0, 0.5));
    m.density_kg_m3 = r.optional("density_kg_m3", m.density_kg_m3, positive);
    r.finish();
    return m;
}

/// A label written as an object key ("127"): decimal digits, optional minus sign, int32.
std::int32_t label_key(const Node& node, const std::string& key)
{
    std::int32_t label = 0;
    const auto result = std::from_chars(key.data(), key.data() + key.size(), label);
    if (key.empty() || result.ec != std::errc() || result.ptr != key.data() + key.size()) {
        node.fail("expected an integer label as key");
    }
    return label;
}

/// Label materials need labels the object can hold: a label selection's own labels, or any
/// label when a scan is taken whole (checked against the scan once it is read). Thresholds,
/// phantoms and meshes give every voxel label 1, so only the default material applies to them.
void read_materials(Reader r, const SceneObject& object, Scene& scene)
{
    if (const std::optional<Node> node = r.optional_node("default")) {
        scene.default_material = read_material(Reader(*node), scene.default_material);
    }
    if (const std::optional<Node> labels = r.optional_node("labels")) {
        const bool whole_scan = object.kind == ObjectKind::volume && object.select.empty();
        const bool by_label = object.kind == ObjectKind::volume && !object.select.labels.empty();
        for (const auto& [key, node] : labels->members()) {
            const std::int32_t label = label_key(node, key);
            if (!whole_scan && !by_label) {
                node.fail("only a scan selected by label (or taken whole) has labels; use materials.default");
            }
            const auto& selected = object.select.labels;
            if (by_label && std::find(selected.begin(), selected.end(), label) == selected.end()) {
                std::string list;
                for (const std::int32_t l : selected) {
                    list += (list.empty() ? "" : ", ") + std::to_string(l);
                }
                node.fail("label " + std::to_string(label) + " is not in object.select.label (" + list + ")");
            }
            if (!scene.label_materials.emplace(label, read_material(Reader(node), scene.default_material)).second) {
                node.fail("label " + std::to_string(label) + " has two entries");
            }
        }
    }
    r.finish();
}

SolverSettings read_solver(Reader r)
{
    SolverSettings s;
    if (const std::optional<Node> node = r.optional_node("type")) {
        s.type = choose_enum(*node, solver_types);
    }
    s.dt_s = r.optional("dt_s", s.dt_s, positive);
    s.cg_tolerance = r.optional("cg_tolerance", s.cg_tolerance, open_range(0.0, 1.0));
    s.cg_max_iterations = r.optional("cg_max_iterations", s.cg_max_iterations, at_least(1));
    r.finish();
    return s;
}

Constraint read_constraint(Reader r)
{
    static constexpr std::array<char, 3> axis_names{'x', 'y', 'z'};
    Constraint c;
    c.type = choose_enum(r.required_node("type"), constraint_types);

    const Node box = r.required_node("box_mm");
    if (!box.value().is_array() || box.value().size() != 2) {
        box.fail_type("[[x, y, z], [x, y, z]] (the box's min and max corners)");
    }
    const std::vector<Node> corners = box.elements();
    c.box_min_mm = as<Eigen::Vector3d>(corners[0]);
    c.box_max_mm = as<Eigen::Vector3d>(corners[1]);
    for (int axis = 0; axis < 3; ++axis) {
        if (c.box_min_mm[axis] > c.box_max_mm[axis]) {
            box.fail(std::string("min corner is above max corner along ") + axis_names[static_cast<std::size_t>(axis)] +
                     " (" + number_text(c.box_min_mm[axis]) + " > " + number_text(c.box_max_mm[axis]) + ")");
        }
    }

    if (c.type == ConstraintType::slide) {
        const Node axes = r.required_node("axes");
        const std::vector<Node> items = axes.elements();
        for (const Node& item : items) {
            const auto axis = static_cast<std::size_t>(choose(item, {"x", "y", "z"}).front() - 'x');
            if (c.slide_axes[axis]) {
                item.fail(std::string("axis ") + axis_names[axis] + " is listed twice");
            }
            c.slide_axes[axis] = true;
        }
        if (items.empty() || items.size() == 3) {
            axes.fail(items.empty() ? "lists no axis; a constraint that allows no motion is \"fixed\""
                                    : "lists every axis; such a constraint holds nothing");
        }
    }
    r.finish(c.type == ConstraintType::fixed ? "for a fixed constraint" : "for a slide constraint");
    return c;
}

ToolSpec read_tool(Reader r, const std::vector<ToolSpec>& declared)
{
    ToolSpec t;
    const Node name = r.required_node("name");
    t.name = as<std::string>(name);
    if (t.name.find_first_not_of(" \t\r\n") == std::string::npos) {
        name.fail("a tool needs a name (the script refers to it)");
    }
    for (std::size_t i = 0; i < declared.size(); ++i) {
        if (declared[i].name == t.name) {
            name.fail("a tool named \"" + t.name + "\" is already declared (tools[" + std::to_string(i) + "])");
        }
    }
    const Node shape = r.required_node("shape");
    t.shape = choose_enum(shape, tool_shapes);
    switch (t.shape) {
    case ToolShape::blade:
        t.size_mm = r.required<Eigen::Vector3d>("size_mm", positive);
        break;
    case ToolShape::scalpel:
        t.size_mm = r.optional("size_mm", default_scalpel_size_mm, positive);
        break;
    case ToolShape::sphere:
        t.radius_mm = r.required<double>("radius_mm", positive);
        break;
    case ToolShape::mesh:
        t.mesh = existing_file(r.required_node("mesh"));
        break;
    }
    r.finish("for a " + as<std::string>(shape) + " tool");
    return t;
}

ScriptEntry read_script_entry(Reader r, const std::vector<ToolSpec>& tools, const ScriptEntry* previous)
{
    ScriptEntry e;
    const Node time = r.required_node("t_s");
    e.t_s = as<double>(time, at_least(0.0));
    if (previous != nullptr && e.t_s < previous->t_s) {
        time.fail(number_text(e.t_s) + " s is before the previous entry's " + number_text(previous->t_s) +
                  " s; entries must be in time order");
    }
    const Node tool = r.required_node("tool");
    e.tool = as<std::string>(tool);
    const auto found = std::find_if(tools.begin(), tools.end(), [&](const ToolSpec& t) { return t.name == e.tool; });
    if (found == tools.end()) {
        std::vector<std::string_view> names;
        std::transform(tools.begin(), tools.end(), std::back_inserter(names), [](const ToolSpec& t) {
            return std::string_view(t.name);
        });
        tool.fail("no tool named \"" + e.tool + "\" in tools (" +
                  (names.empty() ? "none is declared" : "declared: " + quoted_list(names)) + ")");
    }
    e.tool_index = static_cast<std::size_t>(found - tools.begin());
    e.position_mm = r.required<Eigen::Vector3d>("position_mm");
    r.finish();
    return e;
}

/// Keys absent from the file keep their values in `o`.
OutputSettings read_output(Reader r, OutputSettings o)
{
    if (const std::optional<Node> dir = r.optional_node("dir")) {
        o.dir = resolved_path(*dir);
    }
    o.mesh_every_n_frames = r.optional("mesh_every_n_frames", o.mesh_every_n_frames, at_least(1));
    r.finish();
    return o;
}

/// Parser callback that refuses a key given twice in one object: nlohmann keeps the last one
/// silently, and a scene that sets "dt_s" twice is a mistake, not a choice. It tracks the key path
/// of every open object and array so the message names the duplicate like any other error.
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

const Material& Scene::material(std::int32_t label) const
{
    const auto found = label_materials.find(label);
    return found == label_materials.end() ? default_material : found->second;
}

InputError Scene::error(std::string_view key_path, std::string_view problem) const
{
    return located_error(source, std::string(key_path), problem);
}

Scene parse_scene(const nlohmann::json& document, const std::filesystem::path& folder,
                  const std::string& name_for_messages)
{
    const Context context{name_for_messages, std::filesystem::absolute(folder).lexically_normal()};
    Reader root(Node(document, "", context));

    // Take every section first so a misspelt section name is reported before the errors it
    // causes elsewhere (a "toolz" section leaves the script naming undeclared tools).
    const Node object = root.required_node("object");
    const std::optional<Node> materials = root.optional_node("materials");
    const std::optional<Node> solver = root.optional_node("solver");
    const std::optional<Node> gravity = root.optional_node("gravity_m_s2");
    const std::optional<Node> constraints = root.optional_node("constraints");
    const std::optional<Node> tools = root.optional_node("tools");
    const std::optional<Node> script = root.optional_node("script");
    const std::optional<Node> output = root.optional_node("output");
    root.finish();

    Scene scene;
    scene.source = name_for_messages;
    scene.folder = context.folder;
    scene.object = read_object(Reader(object));
    if (materials) {
        read_materials(Reader(*materials), scene.object, scene);
    }
    if (solver) {
        scene.solver = read_solver(Reader(*solver));
    }
    if (gravity) {
        scene.gravity_m_s2 = as<Eigen::Vector3d>(*gravity);
    }
    if (constraints) {
        for (const Node& node : constraints->elements()) {
            scene.constraints.push_back(read_constraint(Reader(node)));
        }
    }
    if (tools) {
        for (const Node& node : tools->elements()) {
            ToolSpec tool = read_tool(Reader(node), scene.tools);
            scene.tools.push_back(std::move(tool));
        }
    }
    if (script) {
        for (const Node& node : script->elements()) {
            const ScriptEntry* previous = scene.script.empty() ? nullptr : &scene.script.back();
            ScriptEntry entry = read_script_entry(Reader(node), scene.tools, previous);
            scene.script.push_back(std::move(entry));
        }
    }
    scene.output.dir = (context.folder / "out").lexically_normal();
    if (output) {
        scene.output = read_output(Reader(*output), scene.output);
    }
    return scene;
}

Scene load_scene(const std::filesystem::path& path)
{
    const std::string source = path.string();
    const std::vector<std::byte> bytes = read_file_bytes(source);
    const std::string text(reinterpret_cast<const char*>(bytes.data()), bytes.size());

    json document;
    try {
        DuplicateKeyCheck check(source);
        document = json::parse(
            text, [&check](int depth, json::parse_event_t event, json& parsed) { return check(depth, event, parsed); },
            /*allow_exceptions=*/true, /*ignore_comments=*/true);
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
    return parse_scene(document, std::filesystem::absolute(path).parent_path(), source);
}

} // namespace vox::io
