#include "io/selection.hpp"

#include "core/error.hpp"
#include "core/progress.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <iterator>
#include <limits>
#include <map>
#include <sstream>
#include <unordered_set>

namespace vox::io {
namespace {

std::string format_number(double v)
{
    std::ostringstream os;
    os << v;
    return os.str();
}

/// The values a file holds, for "nothing selected" messages: the smallest ones with their voxel
/// counts, how many distinct values there are (up to a cap) and how many voxels.
class ValueCensus {
public:
    void add(double value, std::uint64_t voxels = 1)
    {
        m_voxels += voxels;
        if (m_distinct.size() < k_distinct_cap) m_distinct.insert(value);
        // The smallest k_shown values, counted exactly: one pushed out has k_shown smaller values
        // that stay, so it never comes back with a partial count.
        if (m_smallest.size() == k_shown && value > m_smallest.rbegin()->first) return;
        m_smallest[value] += voxels;
        if (m_smallest.size() > k_shown) m_smallest.erase(std::prev(m_smallest.end()));
    }
    [[nodiscard]] std::string describe(const std::string& what) const
    {
        std::ostringstream os;
        const bool capped = m_distinct.size() >= k_distinct_cap;
        os << what << " present (" << (capped ? "more than " : "") << m_distinct.size() << " distinct, in " << m_voxels
           << " voxels; " << (m_distinct.size() > k_shown ? "the smallest" : "smallest first") << ", with their voxels): ";
        bool first = true;
        for (const auto& [value, n] : m_smallest) {
            os << (first ? "" : ", ") << format_number(value) << " (" << n << ")";
            first = false;
        }
        if (m_distinct.size() > k_shown) os << ", ...";
        return os.str();
    }

private:
    static constexpr std::size_t k_shown = 12;
    static constexpr std::size_t k_distinct_cap = 1000000;
    std::map<double, std::uint64_t> m_smallest;
    std::unordered_set<double> m_distinct;
    std::uint64_t m_voxels = 0;
};

/// The label a voxel gets under `s`, or 0 when it is not selected. `stored`/`scaled` are its values.
struct Selector {
    const Selection& s;
    std::int32_t operator()(double stored, double scaled) const
    {
        for (const ThresholdBand& b : s.bands)
            if (scaled >= b.min && scaled <= b.max) return b.label;
        if (!s.bands.empty()) return 0;
        if (s.threshold_min) {
            const bool in = scaled >= *s.threshold_min && (!s.threshold_max || scaled <= *s.threshold_max);
            return in ? 1 : 0;
        }
        if (!s.labels.empty()) {
            for (std::int32_t l : s.labels)
                if (stored == static_cast<double>(l)) return l;
            return 0;
        }
        return stored != 0.0 ? static_cast<std::int32_t>(stored) : 0;
    }
};

/// `v`, a whole number, written out in full ("4000000000", not "4e+09").
std::string whole_number_text(double v)
{
    std::ostringstream os;
    os << std::fixed << std::setprecision(0) << v;
    return os.str();
}

void check_integer_label(const std::string& source, double stored)
{
    if (!std::isfinite(stored) || stored != std::floor(stored))
        throw file_error(source, "value " + format_number(stored) +
                                     " is not an integer label; select voxels with --threshold LO[:HI] instead");
    if (stored < static_cast<double>(std::numeric_limits<std::int32_t>::min()) ||
        stored > static_cast<double>(std::numeric_limits<std::int32_t>::max()))
        throw file_error(source, "label " +
                                     (std::abs(stored) < 1e18 ? whole_number_text(stored) : format_number(stored)) +
                                     " does not fit a 32-bit signed label; select voxels with --threshold LO[:HI] "
                                     "instead");
}

} // namespace

std::string Selection::describe() const
{
    std::string out;
    if (!bands.empty()) {
        out = "threshold bands";
        for (const ThresholdBand& b : bands)
            out += " [" + format_number(b.min) + ", " + format_number(b.max) + "] -> " + std::to_string(b.label);
    } else if (threshold_min) {
        out = "threshold [" + format_number(*threshold_min) + ", " +
              (threshold_max ? format_number(*threshold_max) : std::string("inf")) + "]";
    } else if (labels.empty()) {
        out = "every non-zero voxel";
    } else {
        out = labels.size() == 1 ? "label " : "labels ";
        for (std::size_t i = 0; i < labels.size(); ++i) {
            if (i > 0) out += ',';
            out += std::to_string(labels[i]);
        }
    }
    if (!pieces.empty()) out += "; " + pieces.describe();
    return out;
}

Selection parse_threshold(const std::string& text)
{
    auto parse = [&](const std::string& part) {
        char* end = nullptr;
        const double v = std::strtod(part.c_str(), &end);
        if (part.empty() || end != part.c_str() + part.size() || !std::isfinite(v))
            throw InputError("--threshold " + text + ": '" + part + "' is not a number (expected LO or LO:HI)");
        return v;
    };
    Selection s;
    const auto colon = text.find(':');
    s.threshold_min = parse(text.substr(0, colon));
    if (colon != std::string::npos) {
        s.threshold_max = parse(text.substr(colon + 1));
        if (*s.threshold_max < *s.threshold_min) throw InputError("--threshold " + text + ": LO is greater than HI");
    }
    return s;
}

grid::LabelGrid select_voxels(const Volume& v, const Selection& s)
{
    grid::LabelGrid out(v.index_to_world);
    out.set_metadata("source", v.source);
    // The scan's size: what is written back covers the scan's whole grid (io/label_map_writer.hpp).
    out.set_metadata("scan_dims", std::to_string(v.dims[0]) + " " + std::to_string(v.dims[1]) + " " + std::to_string(v.dims[2]));
    if (v.nifti) out.set_metadata("nifti_transforms", v.nifti->text()); // for label maps written back (label_map_writer)
    const Selector select{s};
    const bool keep_values = s.empty();
    Progress progress("selecting voxels", static_cast<std::uint64_t>(v.dims[2]));
    std::int64_t n = 0;
    for (std::int32_t k = 0; k < v.dims[2]; ++k) {
        for (std::int32_t j = 0; j < v.dims[1]; ++j)
            for (std::int32_t i = 0; i < v.dims[0]; ++i, ++n) {
                const double stored = v.stored(n);
                if (keep_values && stored != 0.0) check_integer_label(v.source, stored);
                const std::int32_t label = select(stored, s.threshold_min || !s.bands.empty() ? v.scaled(n) : stored);
                if (label != 0) out.set({i, j, k}, label);
            }
        progress.update(static_cast<std::uint64_t>(k + 1));
    }
    if (out.active_voxel_count() == 0) {
        ValueCensus census;
        const bool scaled = s.threshold_min.has_value() || !s.bands.empty();
        for (std::int64_t m = 0; m < v.voxel_count(); ++m) census.add(scaled ? v.scaled(m) : v.stored(m));
        throw file_error(v.source, "the selection (" + s.describe() + ") holds no voxel; " + census.describe(scaled ? "values" : "stored values"));
    }
    return s.pieces.empty() ? std::move(out) : select_pieces(out, s.pieces, v.source);
}

grid::LabelGrid select_labels(const grid::LabelGrid& labels, const Selection& s, const std::string& source)
{
    if (s.empty()) {
        if (labels.active_voxel_count() == 0) throw file_error(source, "holds no active voxel");
        return select_pieces(labels, s.pieces, source);
    }
    grid::LabelGrid out(labels.index_to_world());
    out.set_metadata("source", labels.metadata("source").empty() ? source : labels.metadata("source"));
    const Selector select{s};
    labels.for_each_active([&](const grid::Coord& c, std::int32_t label) {
        const std::int32_t l = select(label, label);
        if (l != 0) out.set(c, l);
    });
    if (out.active_voxel_count() == 0) {
        ValueCensus census;
        for (const auto& [l, n] : labels.label_histogram()) census.add(l, n);
        throw file_error(source, "the selection (" + s.describe() + ") holds no voxel; " + census.describe("labels"));
    }
    return s.pieces.empty() ? std::move(out) : select_pieces(out, s.pieces, source);
}

} // namespace vox::io
