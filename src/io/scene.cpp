// The scene schema (docs/scene-format.md), walked with the strict JSON reader (io/json_reader.hpp).

#include "io/scene.hpp"
#include "io/segmentation.hpp"

#include "io/json_reader.hpp"
#include "io/text_parsing.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <optional>
#include <string>
#include <string_view>
#include <tuple>
#include <utility>
#include <vector>

namespace vox::io {

using detail::number_text;

namespace {

constexpr NameTable<SolverType, 3> solver_types{
    {{"dbg", SolverType::dbg}, {"isxfem", SolverType::isxfem}, {"shape_matching", SolverType::shape_matching}}};
constexpr NameTable<SolverMode, 2> solver_modes{
    {{"dynamic", SolverMode::dynamic}, {"static", SolverMode::static_equilibrium}}};
constexpr NameTable<PreconditionerChoice, 4> preconditioners{{{"auto", PreconditionerChoice::automatic},
                                                              {"jacobi", PreconditionerChoice::jacobi},
                                                              {"cholesky", PreconditionerChoice::cholesky},
                                                              {"multigrid", PreconditionerChoice::multigrid}}};
constexpr NameTable<bool, 2> mass_kinds{{{"lumped", true}, {"consistent", false}}};
constexpr NameTable<ConstraintType, 2> constraint_types{
    {{"fixed", ConstraintType::fixed}, {"slide", ConstraintType::slide}}};
constexpr NameTable<ToolShape, 5> tool_shapes{{{"blade", ToolShape::blade},
                                               {"scalpel", ToolShape::scalpel},
                                               {"sphere", ToolShape::sphere},
                                               {"cylinder", ToolShape::cylinder},
                                               {"mesh", ToolShape::mesh}}};
constexpr NameTable<ToolAction, 4> tool_actions{
    {{"push", ToolAction::push}, {"cut", ToolAction::cut}, {"wet", ToolAction::wet}, {"drill", ToolAction::drill}}};
constexpr NameTable<ObstacleShape, 3> obstacle_shapes{
    {{"plane", ObstacleShape::plane}, {"box", ObstacleShape::box}, {"mesh", ObstacleShape::mesh}}};
constexpr NameTable<CutMode, 2> cut_modes{{{"remove", CutMode::remove}, {"separate", CutMode::separate}}};

// ---------------------------------------------------------------------------------------------
// The sections of a scene.
// ---------------------------------------------------------------------------------------------

const Bound positive = greater_than(0.0);

constexpr std::array<char, 3> axis_names{'x', 'y', 'z'};

/// An [x, y, z] array of finite numbers. A JSON file cannot hold NaN or infinity, but a document
/// built in code (parse_scene) can.
Eigen::Vector3d finite_vector(const JsonNode& node)
{
    // Checked before as<>, whose range check would report a NaN as out of range.
    if (node.value().is_array() && node.value().size() == 3) {
        for (const JsonNode& item : node.elements()) {
            if (item.value().is_number_float() && !std::isfinite(item.value().get<double>())) {
                item.fail("must be a finite number");
            }
        }
    }
    return as<Eigen::Vector3d>(node);
}

/// [w, x, y, z]: a rotation as a quaternion of 4 finite numbers, normalised; a norm below 1e-9
/// gives no direction and is refused.
Eigen::Quaterniond unit_quaternion(const JsonNode& node)
{
    if (!node.value().is_array() || node.value().size() != 4) {
        node.fail_type("an array of 4 numbers [w, x, y, z]");
    }
    std::array<double, 4> wxyz{};
    const std::vector<JsonNode> items = node.elements();
    for (std::size_t i = 0; i < 4; ++i) {
        // Checked before as<>, as in finite_vector.
        if (items[i].value().is_number_float() && !std::isfinite(items[i].value().get<double>())) {
            items[i].fail("must be a finite number");
        }
        wxyz[i] = as<double>(items[i]);
    }
    Eigen::Quaterniond q(wxyz[0], wxyz[1], wxyz[2], wxyz[3]);
    double norm = q.norm();
    if (!std::isfinite(norm)) {
        norm = q.coeffs().stableNorm(); // components near the largest double overflow the plain sum of squares
    }
    if (norm < 1e-9) {
        node.fail("the quaternion's norm " + number_text(norm) + " is below 1e-9 (it gives no rotation)");
    }
    q.coeffs() /= norm;
    return q;
}

/// An axis-aligned box [[x, y, z], [x, y, z]]: its min and max corners, world mm.
std::pair<Eigen::Vector3d, Eigen::Vector3d> read_box(const JsonNode& box)
{
    if (!box.value().is_array() || box.value().size() != 2) {
        box.fail_type("[[x, y, z], [x, y, z]] (the box's min and max corners)");
    }
    const std::vector<JsonNode> corners = box.elements();
    const Eigen::Vector3d lo = finite_vector(corners[0]);
    const Eigen::Vector3d hi = finite_vector(corners[1]);
    for (std::size_t axis = 0; axis < 3; ++axis) {
        const auto i = static_cast<Eigen::Index>(axis);
        if (lo[i] > hi[i]) {
            box.fail(std::string("min corner is above max corner along ") + axis_names[axis] + " (" +
                     number_text(lo[i]) + " > " + number_text(hi[i]) + ")");
        }
    }
    return {lo, hi};
}

/// A scalpel's size when the scene gives none: about a No. 10 surgical blade, mm.
const Eigen::Vector3d default_scalpel_size_mm(30.0, 0.5, 8.0);

PieceSelection read_piece_selection(JsonReader& r)
{
    PieceSelection p;
    if (const std::optional<JsonNode> node = r.optional_node("components")) {
        if (node->value().is_string()) {
            const std::string text = as<std::string>(*node);
            if (text == "largest") {
                p.components = PieceSelection::Components::largest;
            } else if (text == "held") {
                p.components = PieceSelection::Components::held;
            } else {
                node->fail("expected \"largest\", \"held\" or a number of pieces (the N largest)");
            }
        } else {
            p.components = PieceSelection::Components::count;
            p.count = static_cast<std::uint32_t>(as<int>(*node, at_least(1.0)));
        }
    }
    if (const std::optional<JsonNode> node = r.optional_node("min_voxels")) {
        p.min_voxels = static_cast<std::uint64_t>(as<int>(*node, at_least(1.0)));
    }
    if (const std::optional<JsonNode> node = r.optional_node("seed_mm")) {
        const std::vector<JsonNode> points = node->elements();
        if (points.empty()) node->fail("must list at least one point [x, y, z]");
        for (const JsonNode& point : points) p.seeds_mm.push_back(finite_vector(point));
    }
    return p;
}

Selection read_selection(JsonReader r)
{
    Selection s;
    s.pieces = read_piece_selection(r);
    if (const std::optional<JsonNode> node = r.optional_node("segment")) {
        if (r.has("label") || r.has("threshold") || r.has("threshold_bands"))
            r.node().fail("takes only one of \"segment\", \"label\", \"threshold\", \"threshold_bands\"");
        const std::vector<JsonNode> items = node->value().is_string() ? std::vector<JsonNode>{*node} : node->elements();
        if (items.empty()) node->fail("must name at least one segment");
        for (const JsonNode& item : items) {
            const auto name = as<std::string>(item);
            if (std::find(s.segments.begin(), s.segments.end(), name) != s.segments.end())
                item.fail("segment '" + name + "' is listed twice");
            s.segments.push_back(name);
        }
        r.finish();
        return s;
    }
    if (const std::optional<JsonNode> node = r.optional_node("threshold_bands")) {
        if (r.has("label") || r.has("threshold")) r.node().fail("takes only one of \"label\", \"threshold\", \"threshold_bands\"");
        const std::vector<JsonNode> items = node->elements();
        if (items.empty()) node->fail("must list at least one band {\"range\": [lo, hi], \"label\": L}");
        for (const JsonNode& item : items) {
            JsonReader band(item);
            ThresholdBand b;
            const JsonNode range = band.required_node("range");
            if (!range.value().is_array() || range.value().size() != 2) range.fail_type("an array [lo, hi] of 2 numbers");
            const std::vector<JsonNode> ends = range.elements();
            b.min = as<double>(ends[0]);
            b.max = as<double>(ends[1]);
            if (b.min > b.max) range.fail("lower bound " + number_text(b.min) + " is above upper bound " + number_text(b.max));
            const JsonNode label = band.required_node("label");
            b.label = as<std::int32_t>(label);
            if (b.label == 0) label.fail("label 0 is the background; give each band a label other than 0");
            band.finish();
            s.bands.push_back(b);
        }
        r.finish();
        return s;
    }
    if (r.has("label") && r.has("threshold")) {
        r.node().fail("takes only one of \"label\", \"threshold\"");
    }
    if (!r.has("label") && !r.has("threshold")) {
        // Pieces of every non-zero voxel.
        if (s.pieces.empty()) r.node().fail("needs label, threshold, components, min_voxels or seed_mm");
    } else if (r.has("label")) {
        const JsonNode node = r.required_node("label");
        // A single label may be written without brackets.
        const std::vector<JsonNode> items = node.value().is_number() ? std::vector<JsonNode>{node} : node.elements();
        if (items.empty()) {
            node.fail("must list at least one label");
        }
        for (const JsonNode& item : items) {
            const auto label = as<std::int32_t>(item);
            if (std::find(s.labels.begin(), s.labels.end(), label) != s.labels.end()) {
                item.fail("label " + std::to_string(label) + " is listed twice");
            }
            s.labels.push_back(label);
        }
    } else {
        const JsonNode node = r.required_node("threshold");
        if (node.value().is_number()) {
            s.threshold_min = as<double>(node);
        } else {
            if (!node.value().is_array() || node.value().size() != 2) {
                node.fail_type("a number or an array [lo, hi] of 2 numbers");
            }
            const std::vector<JsonNode> bounds = node.elements();
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

grid::PhantomSpec read_phantom(JsonReader r)
{
    const JsonNode shape = r.required_node("shape");
    const std::string_view name = choose(shape, {"beam", "block", "sphere", "cylinder", "utube"});
    grid::PhantomSpec p = grid::default_phantom(grid::parse_phantom_shape(std::string(name)));
    const std::optional<JsonNode> voxel = r.optional_node("voxel_mm");
    if (voxel) {
        p.voxel_mm = as<double>(*voxel, positive);
    }

    // The phantom generator needs every size to be a whole number of voxels (docs/phantoms.md);
    // checking here names the key. A size the file gives is named itself; a default size that
    // does not fit the given voxel_mm is reported on voxel_mm.
    struct Extent {
        std::optional<JsonNode> node;
        double mm;
        std::string name;
        bool diameter; ///< mm is twice the key's value
    };
    std::vector<Extent> extents;
    const auto length = [&](std::string_view key, double& field, bool diameter) {
        const std::optional<JsonNode> node = r.optional_node(key);
        if (node) {
            field = as<double>(*node, positive);
        }
        extents.push_back({node, diameter ? 2.0 * field : field, std::string(key), diameter});
    };
    switch (p.shape) {
    case grid::PhantomShape::beam:
    case grid::PhantomShape::block: {
        const std::optional<JsonNode> node = r.optional_node("size_mm");
        if (node) {
            p.size_mm = as<Eigen::Vector3d>(*node, positive);
        }
        for (std::size_t axis = 0; axis < 3; ++axis) {
            extents.push_back({node ? std::optional<JsonNode>(node->elements()[axis]) : std::nullopt,
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

SceneObject read_object(JsonReader r)
{
    SceneObject o;
    const std::string_view kind = r.exactly_one_of({"volume", "phantom", "mesh"});
    if (kind == "volume") {
        o.kind = ObjectKind::volume;
        const JsonNode volume = r.required_node("volume");
        o.file = resolved_path(volume);
        std::error_code error;
        if (!std::filesystem::is_directory(o.file, error)) o.file = existing_file(volume); // a DICOM export is a folder
        if (const std::optional<JsonNode> series = r.optional_node("series")) {
            if (series->value().is_number_integer())
                o.series = std::to_string(as<int>(*series, closed_range(1, 1 << 30)));
            else if (series->value().is_string() && !as<std::string>(*series).empty())
                o.series = as<std::string>(*series);
            else
                series->fail("expected a series number (1, 2, ... as `voxsculpt info` lists them) or a SeriesInstanceUID");
        }
        if (const std::optional<JsonNode> select = r.optional_node("select")) {
            o.select = read_selection(JsonReader(*select));
        }
        if (is_segmentation_path(o.file.string())) {
            // Named segments are checked now, before any work; their colours are the pictures'.
            if (!o.select.labels.empty() || o.select.threshold_min || !o.select.bands.empty())
                r.required_node("select").fail("a 3D Slicer segmentation is selected by \"segment\" (names), not by label or threshold");
            const std::vector<Segment> all = read_segments(o.file.string());
            try {
                const std::vector<Segment> picked = pick_segments(all, o.select.segments, o.file.string());
                for (std::size_t k = 0; k < picked.size(); ++k) {
                    o.label_colors[static_cast<std::int32_t>(k + 1)] = picked[k].color;
                    o.label_names[static_cast<std::int32_t>(k + 1)] = picked[k].name;
                }
            } catch (const InputError& e) {
                r.required_node("select").fail(e.what());
            }
        } else if (!o.select.segments.empty()) {
            r.required_node("select").fail("\"segment\" picks segments of a 3D Slicer segmentation (.seg.nrrd)");
        }
    } else if (kind == "phantom") {
        o.kind = ObjectKind::phantom;
        o.phantom = read_phantom(JsonReader(r.required_node("phantom")));
    } else {
        o.kind = ObjectKind::mesh;
        o.file = existing_file(r.required_node("mesh"));
        if (const std::optional<JsonNode> voxel = r.optional_node("voxel_mm")) {
            o.voxel_mm = as<double>(*voxel, positive);
        }
        o.scale_mm_per_unit = r.optional("scale_mm_per_unit", o.scale_mm_per_unit, positive);
    }
    if (const std::optional<JsonNode> levels = r.optional_node("levels")) {
        if (levels->value().is_string()) {
            if (as<std::string>(*levels) != "auto") levels->fail("expected an integer 0 to 6, \"auto\" or {\"fine\", \"coarse\", \"fine_radius_mm\"}");
            o.auto_levels = true;
        } else if (levels->value().is_object()) {
            JsonReader l(*levels);
            MixedLevelsSpec m;
            m.fine = l.required<int>("fine", closed_range(1, 5));
            m.coarse = l.required<int>("coarse", closed_range(2, 6));
            m.fine_radius_mm = l.required<double>("fine_radius_mm", positive);
            if (m.fine >= m.coarse) l.required_node("coarse").fail("must be coarser than \"fine\" (" + std::to_string(m.fine) + "), got " + std::to_string(m.coarse));
            o.levels = m.coarse; // the grid is built up to it
            o.mixed_levels = m;
        } else {
            o.levels = as<int>(*levels, closed_range(0, 6));
        }
    }
    const std::optional<JsonNode> budget = r.optional_node("step_budget_ms");
    const std::optional<JsonNode> error = r.optional_node("max_error");
    if (budget) o.step_budget_ms = as<double>(*budget, positive);
    if (error) o.max_error = as<double>(*error, open_range(0.0, 1.0));
    if (o.auto_levels && budget.has_value() == error.has_value()) {
        (budget ? *budget : r.required_node("levels")).fail("\"levels\": \"auto\" needs exactly one of step_budget_ms and max_error");
    }
    if (!o.auto_levels && (budget || error)) {
        (budget ? *budget : *error).fail("only meaningful with \"levels\": \"auto\"");
    }
    if (const std::optional<JsonNode> node = r.optional_node("smooth_surface")) o.smooth_surface = as<bool>(*node);
    if (const std::optional<JsonNode> node = r.optional_node("unheld_pieces")) {
        static constexpr NameTable<UnheldPieces, 4> names{{{"hold", UnheldPieces::hold},
                                                           {"fall", UnheldPieces::fall},
                                                           {"leave_out", UnheldPieces::leave_out},
                                                           {"rigid", UnheldPieces::rigid}}};
        o.unheld = choose_enum(*node, names);
        o.unheld_given = true;
    }
    r.finish("for a " + std::string(kind) + " object");
    return o;
}

/// Keys absent from the file keep their values in `m`.
Material read_material(JsonReader r, Material m)
{
    m.youngs_modulus_pa = r.optional("youngs_modulus_pa", m.youngs_modulus_pa, positive);
    m.poisson_ratio = r.optional("poisson_ratio", m.poisson_ratio, open_range(-1.0, 0.5));
    m.density_kg_m3 = r.optional("density_kg_m3", m.density_kg_m3, positive);
    if (const std::optional<JsonNode> node = r.optional_node("plasticity")) {
        JsonReader p(*node);
        Plasticity plastic = m.plasticity.value_or(Plasticity{});
        plastic.yield_strain = p.optional("yield_strain", plastic.yield_strain, positive);
        plastic.creep_per_s = p.optional("creep_per_s", plastic.creep_per_s, at_least(0.0));
        plastic.max_strain = p.optional("max_strain", plastic.max_strain, positive);
        p.finish();
        m.plasticity = plastic;
    }
    const std::optional<JsonNode> wetting = r.optional_node("wetting");
    if (wetting) {
        JsonReader w(*wetting);
        m.wetting.stiffness_ratio = w.optional("stiffness_ratio", m.wetting.stiffness_ratio, half_open_range(0.0, 1.0));
        m.wetting.yield_ratio = w.optional("yield_ratio", m.wetting.yield_ratio, half_open_range(0.0, 1.0));
        w.finish();
    }
    const std::optional<JsonNode> rigid = r.optional_node("rigid");
    if (rigid) m.rigid = as<bool>(*rigid);
    if (m.rigid && (m.plasticity || wetting)) {
        const std::string problem = "a rigid material does not deform, so it has no plasticity or wetting";
        (rigid ? *rigid : r.node()).fail(problem);
    }
    r.finish();
    return m;
}

/// A label written as an object key ("127"): decimal digits, optional minus sign, int32.
std::int32_t label_key(const JsonNode& node, const std::string& key)
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
void read_materials(JsonReader r, const SceneObject& object, Scene& scene)
{
    if (const std::optional<JsonNode> node = r.optional_node("default")) {
        scene.default_material = read_material(JsonReader(*node), scene.default_material);
    }
    if (const std::optional<JsonNode> labels = r.optional_node("labels")) {
        const bool whole_scan = object.kind == ObjectKind::volume && object.select.empty();
        const bool by_band = object.kind == ObjectKind::volume && !object.select.bands.empty();
        const bool by_label = by_band || (object.kind == ObjectKind::volume && !object.select.labels.empty());
        std::vector<std::int32_t> selected = object.select.labels;
        for (const ThresholdBand& b : object.select.bands) selected.push_back(b.label);
        for (const auto& [key, node] : labels->members()) {
            const std::int32_t label = label_key(node, key);
            if (!whole_scan && !by_label) {
                node.fail("only a scan selected by label (or taken whole) has labels; use materials.default");
            }
            if (by_label && std::find(selected.begin(), selected.end(), label) == selected.end()) {
                std::string list;
                for (const std::int32_t l : selected) {
                    list += (list.empty() ? "" : ", ") + std::to_string(l);
                }
                node.fail("label " + std::to_string(label) + " is not in object.select." +
                          (by_band ? "threshold_bands" : "label") + " (" + list + ")");
            }
            if (!scene.label_materials.emplace(label, read_material(JsonReader(node), scene.default_material)).second) {
                node.fail("label " + std::to_string(label) + " has two entries");
            }
        }
    }
    r.finish();
}

SolverSettings read_solver(JsonReader r)
{
    SolverSettings s;
    if (const std::optional<JsonNode> node = r.optional_node("type")) {
        s.type = choose_enum(*node, solver_types);
    }
    if (const std::optional<JsonNode> node = r.optional_node("mode")) {
        s.mode = choose_enum(*node, solver_modes);
    }
    s.dt_s = r.optional("dt_s", s.dt_s, half_open_range(0.0, 10.0)); // beyond 10 s no interactive scene means it
    s.cg_tolerance = r.optional("cg_tolerance", s.cg_tolerance, open_range(0.0, 1.0));
    s.cg_max_iterations = r.optional("cg_max_iterations", s.cg_max_iterations, at_least(1));
    s.rayleigh_mass_per_s = r.optional("rayleigh_mass_per_s", s.rayleigh_mass_per_s, at_least(0.0));
    s.rayleigh_stiffness_s = r.optional("rayleigh_stiffness_s", s.rayleigh_stiffness_s, at_least(0.0));
    s.newton_max_iterations = r.optional("newton_max_iterations", s.newton_max_iterations, at_least(1));
    if (const std::optional<JsonNode> node = r.optional_node("preconditioner")) {
        s.preconditioner = choose_enum(*node, preconditioners);
    }
    if (const std::optional<JsonNode> node = r.optional_node("mass")) {
        s.lumped_mass = choose_enum(*node, mass_kinds);
    }
    s.isxfem_k = r.optional("k", s.isxfem_k, closed_range(0.0, 1.0));
    s.isxfem_regularisation_lambda = r.optional("regularisation_lambda", s.isxfem_regularisation_lambda, at_least(0.0));
    s.isxfem_regularisation_threshold = r.optional("regularisation_threshold", s.isxfem_regularisation_threshold, closed_range(0.0, 1.0));
    s.sm_cluster_levels = r.optional("cluster_levels", s.sm_cluster_levels, closed_range(0, 5));
    s.sm_adaptive = r.optional("adaptive", s.sm_adaptive);
    s.sm_global_step = r.optional("global_step", s.sm_global_step);
    s.sm_max_iterations = r.optional("max_iterations", s.sm_max_iterations, closed_range(1, 100000));
    s.sm_termination_rate = r.optional("termination_rate", s.sm_termination_rate, open_range(0.0, 1.0));
    s.sm_subdivision_strain = r.optional("subdivision_strain", s.sm_subdivision_strain, closed_range(0.0, 1.0));
    r.finish();
    return s;
}

Constraint read_constraint(JsonReader r)
{
    Constraint c;
    c.type = choose_enum(r.required_node("type"), constraint_types);
    std::tie(c.box_min_mm, c.box_max_mm) = read_box(r.required_node("box_mm"));

    // fixed holds every axis (the default); slide holds the axes it lists.
    c.held_axes = {true, true, true};
    if (c.type == ConstraintType::slide) {
        c.held_axes = {false, false, false};
        const JsonNode axes = r.required_node("axes");
        const std::vector<JsonNode> items = axes.elements();
        for (const JsonNode& item : items) {
            const auto axis = static_cast<std::size_t>(choose(item, {"x", "y", "z"}).front() - 'x');
            if (c.held_axes[axis]) {
                item.fail(std::string("axis ") + axis_names[axis] + " is listed twice");
            }
            c.held_axes[axis] = true;
        }
        if (items.empty()) {
            axes.fail("lists no axis; such a constraint holds nothing");
        }
        if (items.size() == 3) {
            axes.fail("lists every axis; that is a fixed constraint (\"type\": \"fixed\")");
        }
    }
    r.finish(c.type == ConstraintType::fixed ? "for a fixed constraint" : "for a slide constraint");
    return c;
}

Load read_load(JsonReader r)
{
    Load l;
    std::tie(l.box_min_mm, l.box_max_mm) = read_box(r.required_node("box_mm"));
    const JsonNode force = r.required_node("force_n");
    l.force_n = finite_vector(force);
    if (l.force_n.norm() > 1e6) // a hundred tonnes: no scene of a body means it, and the step only projects energy away
        force.fail("is stronger than 1e6 N (about 100 tonnes), the most a load may ask");
    r.finish();
    return l;
}

Obstacle read_obstacle(JsonReader r)
{
    Obstacle o;
    const JsonNode shape = r.required_node("shape");
    o.shape = choose_enum(shape, obstacle_shapes);
    switch (o.shape) {
    case ObstacleShape::plane: {
        o.point_mm = finite_vector(r.required_node("point_mm"));
        const JsonNode normal = r.required_node("normal");
        o.normal = finite_vector(normal);
        if (!(o.normal.norm() >= 1e-9)) normal.fail("has no direction (its length is below 1e-9)");
        o.normal.normalize();
        break;
    }
    case ObstacleShape::box: {
        const JsonNode box = r.required_node("box_mm");
        std::tie(o.box_min_mm, o.box_max_mm) = read_box(box);
        if ((o.box_max_mm - o.box_min_mm).minCoeff() <= 0.0) box.fail("is flat (an obstacle box needs a thickness on every axis)");
        break;
    }
    case ObstacleShape::mesh:
        o.mesh = existing_file(r.required_node("mesh"));
        if (const std::optional<JsonNode> node = r.optional_node("position_mm")) o.position_mm = finite_vector(*node);
        if (const std::optional<JsonNode> node = r.optional_node("orientation_wxyz")) o.orientation = unit_quaternion(*node);
        o.scale = r.optional("scale", o.scale, half_open_range(0.0, 1e6));
        break;
    }
    o.friction = r.optional("friction", o.friction, closed_range(0.0, 10.0));
    o.stiffness_n_per_mm = r.optional("stiffness_n_per_mm", o.stiffness_n_per_mm, half_open_range(0.0, 1e4));
    r.finish("for a " + as<std::string>(shape) + " obstacle");
    return o;
}

PieceContactSettings read_piece_contact(const JsonNode& node)
{
    PieceContactSettings p;
    if (node.value().is_boolean()) {
        p.enabled = node.value().get<bool>();
        return p;
    }
    if (!node.value().is_object()) node.fail("must be true, false or an object with \"stiffness_n_per_mm\"");
    p.enabled = true;
    JsonReader r(node);
    p.stiffness_n_per_mm = r.optional("stiffness_n_per_mm", p.stiffness_n_per_mm, half_open_range(0.0, 1e4));
    r.finish();
    return p;
}

WetRegion read_wet_region(JsonReader r)
{
    WetRegion w;
    std::tie(w.box_min_mm, w.box_max_mm) = read_box(r.required_node("box_mm"));
    w.water = r.optional("water", w.water, closed_range(0.0, 1.0));
    r.finish();
    return w;
}

ToolSpec read_tool(JsonReader r, const std::vector<ToolSpec>& declared, SolverType type)
{
    ToolSpec t;
    const JsonNode name = r.required_node("name");
    t.name = as<std::string>(name);
    if (t.name.find_first_not_of(" \t\r\n") == std::string::npos) {
        name.fail("a tool needs a name (the script refers to it)");
    }
    for (std::size_t i = 0; i < declared.size(); ++i) {
        if (declared[i].name == t.name) {
            name.fail("a tool named \"" + t.name + "\" is already declared (tools[" + std::to_string(i) + "])");
        }
    }
    const JsonNode shape = r.required_node("shape");
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
    case ToolShape::cylinder:
        t.radius_mm = r.required<double>("radius_mm", positive);
        t.length_mm = r.required<double>("length_mm", positive);
        break;
    case ToolShape::mesh:
        t.mesh = existing_file(r.required_node("mesh"));
        break;
    }
    // Contact and cutting. Every tool takes every key; a key that does not apply to the tool's
    // action (cut_mode on a push tool) is accepted and has no effect.
    t.action = default_tool_action(t.shape);
    if (const std::optional<JsonNode> node = r.optional_node("action")) {
        t.action = choose_enum(*node, tool_actions);
    }
    t.cut_mode = default_cut_mode(type);
    if (const std::optional<JsonNode> node = r.optional_node("cut_mode")) {
        t.cut_mode = choose_enum(*node, cut_modes);
        t.cut_mode_given = true;
    }
    t.push_margin_mm = r.optional("push_margin_mm", t.push_margin_mm, closed_range(0.0, 100.0));
    t.contact_stiffness_n_per_mm =
        r.optional("contact_stiffness_n_per_mm", t.contact_stiffness_n_per_mm, half_open_range(0.0, 1e4));
    if (r.optional_node("coupling_stiffness_n_per_mm"))
        t.coupling_stiffness_n_per_mm = r.optional("coupling_stiffness_n_per_mm", 0.0, half_open_range(0.0, 1e6));
    t.cut_pressure_pa = r.optional("cut_pressure_pa", t.cut_pressure_pa, half_open_range(0.0, 1e9));
    t.wet_rate_per_s = r.optional("wet_rate_per_s", t.wet_rate_per_s, half_open_range(0.0, 1e3));
    t.burr_speed_rpm = r.optional("burr_speed_rpm", t.burr_speed_rpm, half_open_range(0.0, 1e6));
    t.drill_rate_mm3_per_n_rev = r.optional("drill_rate_mm3_per_n_rev", t.drill_rate_mm3_per_n_rev, half_open_range(0.0, 1.0));
    if (const std::optional<JsonNode> node = r.optional_node("device_frame")) {
        JsonReader f(*node);
        DeviceFrameSpec frame;
        if (const std::optional<JsonNode> origin = f.optional_node("origin_mm")) frame.origin_mm = finite_vector(*origin);
        if (const std::optional<JsonNode> turn = f.optional_node("rotation_wxyz")) frame.rotation = unit_quaternion(*turn);
        frame.scale = f.optional("scale", frame.scale, half_open_range(0.0, 100.0));
        f.finish("for a device frame");
        t.device_frame = frame;
    }
    if (const std::optional<JsonNode> node = r.optional_node("haptic_subdivision")) {
        t.haptic_subdivision = r.optional("haptic_subdivision", t.haptic_subdivision, closed_range(-1, 3));
        // The patch's layer sits on the surface it was built on: a cut or a burr changes that
        // surface under it every frame (measured: a blade's patch swung its force by 1 N a tick).
        if (t.haptic_subdivision >= 0 && (t.action == ToolAction::cut || t.action == ToolAction::drill))
            node->fail("haptic subdivision is for tools that push or wet: a tool that cuts or drills changes the surface under its patch every "
                       "frame (give this tool \"action\": \"push\", or leave the key out)");
    }
    if (const std::optional<JsonNode> node = r.optional_node("two_phase")) {
        t.two_phase = as<bool>(*node);
        if (t.two_phase && (t.action != ToolAction::cut || t.cut_mode != CutMode::separate))
            node->fail("two-phase cutting marks a cut to open whole: it needs \"action\": \"cut\" and \"cut_mode\": \"separate\"");
    }
    r.finish("for a " + as<std::string>(shape) + " tool");
    return t;
}

ScriptEntry read_script_entry(JsonReader r, const std::vector<ToolSpec>& tools, const ScriptEntry* previous)
{
    ScriptEntry e;
    const JsonNode time = r.required_node("t_s");
    e.t_s = as<double>(time, at_least(0.0));
    if (previous != nullptr && e.t_s < previous->t_s) {
        time.fail(number_text(e.t_s) + " s is before the previous entry's " + number_text(previous->t_s) +
                  " s; entries must be in time order");
    }
    const JsonNode tool = r.required_node("tool");
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
    if (const std::optional<JsonNode> node = r.optional_node("orientation_wxyz")) {
        e.orientation = unit_quaternion(*node);
    }
    r.finish();
    return e;
}

/// Keys absent from the file keep their values in `o`.
OutputSettings read_output(JsonReader r, OutputSettings o)
{
    if (const std::optional<JsonNode> dir = r.optional_node("dir")) {
        o.dir = resolved_path(*dir);
    }
    o.mesh_every_n_frames = r.optional("mesh_every_n_frames", o.mesh_every_n_frames, at_least(1));
    o.vtu_every_n_frames = r.optional("vtu_every_n_frames", o.vtu_every_n_frames, at_least(1));
    if (const std::optional<JsonNode> volumes = r.optional_node("volumes")) {
        o.volumes.clear();
        for (const JsonNode& item : volumes->elements()) {
            const std::string format(choose(item, {"vdb", "nii.gz", "nii", "nrrd", "seg.nrrd"}));
            if (std::find(o.volumes.begin(), o.volumes.end(), format) != o.volumes.end()) item.fail("\"" + format + "\" is listed twice");
            o.volumes.push_back(format);
        }
    }
    r.finish();
    return o;
}

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

/// What two levels in one model ("levels" as an object) do not run with yet.
static void check_mixed_levels(const Scene& scene)
{
    if (scene.object.auto_levels) throw scene.error("object.levels", "is either \"auto\" or two levels, not both");
    if (scene.solver.type != SolverType::dbg)
        throw scene.error("object.levels", "two levels run on the branched grid only (\"solver\": {\"type\": \"dbg\"})");
    if (scene.solver.preconditioner == PreconditionerChoice::cholesky || scene.solver.preconditioner == PreconditionerChoice::multigrid)
        throw scene.error("solver.preconditioner", "two levels solve with Jacobi (\"auto\" or \"jacobi\")");
}

Scene parse_scene(const nlohmann::json& document, const std::filesystem::path& folder,
                  const std::string& name_for_messages)
{
    const JsonContext context{name_for_messages, std::filesystem::absolute(folder).lexically_normal()};
    JsonReader root(JsonNode(document, "", context));

    // Take every section first so a misspelt section name is reported before the errors it
    // causes elsewhere (a "toolz" section leaves the script naming undeclared tools).
    const JsonNode object = root.required_node("object");
    const std::optional<JsonNode> materials = root.optional_node("materials");
    const std::optional<JsonNode> solver = root.optional_node("solver");
    const std::optional<JsonNode> gravity = root.optional_node("gravity_m_s2");
    const std::optional<JsonNode> constraints = root.optional_node("constraints");
    const std::optional<JsonNode> obstacles = root.optional_node("obstacles");
    const std::optional<JsonNode> piece_contact = root.optional_node("piece_contact");
    const std::optional<JsonNode> loads = root.optional_node("loads");
    const std::optional<JsonNode> wet_regions = root.optional_node("wet_regions");
    const std::optional<JsonNode> tools = root.optional_node("tools");
    const std::optional<JsonNode> script = root.optional_node("script");
    const std::optional<JsonNode> output = root.optional_node("output");
    root.finish();

    Scene scene;
    scene.source = name_for_messages;
    scene.folder = context.folder;
    scene.object = read_object(JsonReader(object));
    if (materials) {
        read_materials(JsonReader(*materials), scene.object, scene);
    }
    if (solver) {
        scene.solver = read_solver(JsonReader(*solver));
    }
    if (gravity) {
        scene.gravity_m_s2 = finite_vector(*gravity);
        if (scene.gravity_m_s2.norm() > 1e3) // 100 g: beyond that no scene means it, and steps only create energy
            gravity->fail("is stronger than 1000 m/s^2 (about 100 g), the most a scene may ask");
    }
    if (constraints) {
        for (const JsonNode& node : constraints->elements()) {
            scene.constraints.push_back(read_constraint(JsonReader(node)));
        }
    }
    // "components": "held" and "unheld_pieces" need the boxes the constraints reach (any object kind).
    for (const Constraint& c : scene.constraints) {
        scene.object.select.pieces.held_boxes.emplace_back(c.box_min_mm, c.box_max_mm);
    }
    if (obstacles) {
        for (const JsonNode& node : obstacles->elements()) {
            scene.obstacles.push_back(read_obstacle(JsonReader(node)));
        }
        // An object given something to rest on is let go onto it unless the file says otherwise.
        if (!scene.obstacles.empty() && !scene.object.unheld_given) scene.object.unheld = UnheldPieces::fall;
    }
    if (piece_contact) scene.piece_contact = read_piece_contact(*piece_contact);
    if (loads) {
        for (const JsonNode& node : loads->elements()) {
            scene.loads.push_back(read_load(JsonReader(node)));
        }
    }
    if (wet_regions) {
        for (const JsonNode& node : wet_regions->elements()) {
            scene.wet_regions.push_back(read_wet_region(JsonReader(node)));
        }
    }
    if (tools) {
        for (const JsonNode& node : tools->elements()) {
            ToolSpec tool = read_tool(JsonReader(node), scene.tools, scene.solver.type);
            scene.tools.push_back(std::move(tool));
        }
    }
    if (script) {
        for (const JsonNode& node : script->elements()) {
            const ScriptEntry* previous = scene.script.empty() ? nullptr : &scene.script.back();
            ScriptEntry entry = read_script_entry(JsonReader(node), scene.tools, previous);
            scene.script.push_back(std::move(entry));
        }
    }
    if (scene.object.mixed_levels) check_mixed_levels(scene);
    scene.output.dir = (context.folder / "out").lexically_normal();
    if (output) {
        scene.output = read_output(JsonReader(*output), scene.output);
    }
    return scene;
}

std::string_view solver_type_name(SolverType type)
{
    for (const auto& [name, value] : solver_types)
        if (value == type) return name;
    return "dbg";
}

SolverType solver_type_named(std::string_view name)
{
    for (const auto& [text, value] : solver_types)
        if (text == name) return value;
    throw InputError("--solver: \"" + std::string(name) + "\" is not a method (dbg, isxfem or shape_matching)");
}

std::string_view preconditioner_name(PreconditionerChoice p)
{
    for (const auto& [name, value] : preconditioners)
        if (value == p) return name;
    return "auto";
}

CutMode default_cut_mode(SolverType type) { return type == SolverType::isxfem ? CutMode::separate : CutMode::remove; }

void use_method(Scene& scene, SolverType type)
{
    scene.solver.type = type;
    for (ToolSpec& t : scene.tools)
        if (!t.cut_mode_given) t.cut_mode = default_cut_mode(type);
}

Scene load_scene(const std::filesystem::path& path)
{
    const nlohmann::json document = read_json_file(path);
    return parse_scene(document, std::filesystem::absolute(path).parent_path(), path.string());
}

bool smooths_surface(const SceneObject& object, SolverType solver)
{
    return object.smooth_surface.value_or(object.kind != ObjectKind::phantom && solver != SolverType::isxfem);
}

} // namespace vox::io
