#include "io/piece_selection.hpp"

#include "io/box.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace vox::io {
namespace {

std::string point_text(const Eigen::Vector3d& p)
{
    std::ostringstream os;
    os << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
    return os.str();
}

} // namespace

std::string count_text(std::uint64_t n)
{
    std::string s = std::to_string(n);
    for (int at = static_cast<int>(s.size()) - 3; at > 0; at -= 3) s.insert(static_cast<std::size_t>(at), ",");
    return s;
}

std::string PieceSelection::describe() const
{
    std::string out;
    switch (components) {
    case Components::all: out = seeds_mm.empty() ? "every piece" : ""; break;
    case Components::largest: out = "the largest piece"; break;
    case Components::count: out = "the " + std::to_string(count) + " largest pieces"; break;
    case Components::held: out = "the pieces a constraint holds"; break;
    }
    if (!seeds_mm.empty())
        out += (out.empty() ? "" : " and ") + std::string("the pieces holding ") + std::to_string(seeds_mm.size()) +
               (seeds_mm.size() == 1 ? " seed point" : " seed points");
    if (min_voxels > 0) out += ", of at least " + count_text(min_voxels) + " voxels";
    return out;
}

std::vector<bool> pieces_in_boxes(const grid::LabelGrid& labels, const grid::VoxelPieces& pieces,
                                  const std::vector<Eigen::AlignedBox3d>& boxes)
{
    std::vector<bool> in(pieces.size(), false);
    if (boxes.empty()) return in;
    // A constraint holds the material whose voxel centres lie in its box (sim/supports.hpp).
    const auto& coords = pieces.voxels();
    const auto& which = pieces.voxel_pieces();
    for (std::size_t v = 0; v < coords.size(); ++v) {
        if (in[which[v]]) continue;
        const Eigen::Vector3d c = labels.index_to_world(coords[v].cast<double>());
        for (const Eigen::AlignedBox3d& b : boxes)
            if (in_box(c, b.min(), b.max())) {
                in[which[v]] = true;
                break;
            }
    }
    return in;
}

std::vector<bool> kept_pieces(const grid::LabelGrid& labels, const grid::VoxelPieces& pieces,
                              const PieceSelection& s, const std::string& source)
{
    const std::size_t n = pieces.size();
    std::vector<bool> keep(n, s.components == PieceSelection::Components::all && s.seeds_mm.empty());
    switch (s.components) {
    case PieceSelection::Components::all: break;
    case PieceSelection::Components::largest:
        if (n > 0) keep[0] = true;
        break;
    case PieceSelection::Components::count:
        for (std::size_t p = 0; p < std::min<std::size_t>(n, s.count); ++p) keep[p] = true;
        break;
    case PieceSelection::Components::held: {
        if (s.held_boxes.empty())
            throw file_error(source, "\"components\": \"held\" keeps the pieces a constraint box holds, and there "
                                     "is no constraint");
        const std::vector<bool> held = pieces_in_boxes(labels, pieces, s.held_boxes);
        for (std::size_t p = 0; p < n; ++p) keep[p] = keep[p] || held[p];
        break;
    }
    }
    const Eigen::Matrix4d to_index = labels.index_to_world().inverse();
    for (std::size_t k = 0; k < s.seeds_mm.size(); ++k) {
        const Eigen::Vector3d ijk = (to_index * s.seeds_mm[k].homogeneous()).head<3>();
        const grid::Coord c(static_cast<std::int32_t>(std::lround(ijk.x())), static_cast<std::int32_t>(std::lround(ijk.y())),
                            static_cast<std::int32_t>(std::lround(ijk.z())));
        const std::uint32_t p = pieces.piece_at(c);
        if (p == grid::VoxelPieces::none) {
            // Say how far the nearest selected voxel is, so the user can move the point.
            double best = std::numeric_limits<double>::max();
            std::uint32_t best_piece = 0;
            const auto& coords = pieces.voxels();
            for (std::size_t v = 0; v < coords.size(); ++v) {
                const double d = (labels.index_to_world(coords[v].cast<double>()) - s.seeds_mm[k]).norm();
                if (d < best) {
                    best = d;
                    best_piece = pieces.voxel_pieces()[v];
                }
            }
            std::ostringstream os;
            os << "seed_mm[" << k << "] " << point_text(s.seeds_mm[k]) << " mm lies in no selected voxel";
            if (!coords.empty()) os << "; the nearest is " << best << " mm away, in piece " << best_piece + 1;
            throw file_error(source, os.str());
        }
        keep[p] = true;
    }
    for (std::size_t p = 0; p < n; ++p)
        if (pieces.pieces()[p].voxels < s.min_voxels) keep[p] = false;
    if (std::find(keep.begin(), keep.end(), true) == keep.end()) {
        std::ostringstream os;
        os << "keeping " << s.describe() << " leaves no voxel (" << describe_pieces(pieces) << ")";
        throw file_error(source, os.str());
    }
    return keep;
}

grid::LabelGrid select_pieces(const grid::LabelGrid& labels, const PieceSelection& s, const std::string& source)
{
    if (s.empty()) return labels.clone();
    const grid::VoxelPieces pieces(labels);
    return grid::keep_pieces(labels, pieces, kept_pieces(labels, pieces, s, source));
}

std::string describe_pieces(const grid::VoxelPieces& pieces, std::size_t at_most)
{
    std::ostringstream os;
    os << pieces.size() << (pieces.size() == 1 ? " piece" : " pieces");
    for (std::size_t p = 0; p < std::min(at_most, pieces.size()); ++p)
        os << (p == 0 ? ": " : ", ") << p + 1 << " (" << count_text(pieces.pieces()[p].voxels)
           << (pieces.pieces()[p].voxels == 1 ? " voxel)" : " voxels)");
    if (pieces.size() > at_most) os << ", ...";
    return os.str();
}

} // namespace vox::io
