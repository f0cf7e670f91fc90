#include "isxfem/cut_closure.hpp"

#include "core/union_find.hpp"
#include "isxfem/polygon_triangulation.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <map>
#include <set>
#include <unordered_map>

namespace vox::isxfem {
namespace {

using VertexEdge = std::pair<int, int>;                   ///< a surface edge, sorted
using NodeEdge = std::pair<std::uint32_t, std::uint32_t>; ///< a tetrahedron edge, sorted

/// Where the surface's triangles cross the cut: on an edge, in the crack or not.
struct Crossing {
    Eigen::Vector3d x = Eigen::Vector3d::Zero();
    std::size_t tet = 0; ///< holding it
    std::array<double, 4> bary{};
    bool inside = false;           ///< in the crack: one point per side
    unsigned region = 0;           ///< its region (XfemElement::region_at) apart from this cut's side
    std::array<int, 2> id{-1, -1}; ///< its point on each side (the same twice outside the crack), once placed
    std::int32_t label = 0;
};

/// Where S's boundary crosses R's, inside a triangle: the crack's front meets the surface.
struct Front {
    int id = -1; ///< its point, shared by both sides
    Eigen::Vector3d x = Eigen::Vector3d::Zero();
    bool entering = false; ///< S's boundary (material on its left) enters the crack here
    int segment = -1;      ///< R's boundary segment it lies on
    double along = 0.0;    ///< where on it, 0 at its start
    int chain = -1;        ///< the run of S's boundary inside R it starts or ends
};

/// A segment of R's boundary, R on its left (seen from the cut's normal there): on the face of a cut
/// tetrahedron whose neighbour across it is not cut by this cut.
struct Segment {
    NodeEdge from, to;
    Eigen::Vector3d x_from, x_to;
    std::size_t tet = 0;
    int face = 0; ///< the corner opposite
};

/// A crack face's boundary: each corner's point per side and its rest position.
struct Loop {
    std::vector<std::array<int, 2>> ids;
    std::vector<Eigen::Vector3d> x;
    bool slit = false; ///< closed along a front
};

/// One cut's closing (see the header): the state of a single call of CutClosure::close.
class Closer {
public:
    Closer(const XfemModel& model, const std::vector<std::array<std::int32_t, 4>>& neighbours, int cut, std::vector<SurfacePoint>& points,
           std::vector<std::int32_t>* crack_of)
        : m_model(model), m_neighbours(neighbours), m_cut(cut), m_surface(model.cut_surface(cut)), m_points(points), m_crack_of(crack_of)
    {
        m_reach = m_surface.bounds();
        if (!m_surface.is_plane()) {
            m_reach.extend(m_reach.min() - Eigen::Vector3d::Constant(model.longest_edge()));
            m_reach.extend(m_reach.max() + Eigen::Vector3d::Constant(model.longest_edge()));
        }
        build_boundary();
    }

    void split(std::vector<Eigen::Vector3i>& triangles);
    void fill(std::vector<Eigen::Vector3i>& triangles);
    ClosureCounts counts;

private:
    /// The cut's level at a point: a plane's; a swept cut's interpolated from its tetrahedron's
    /// nodes' (XfemModel::level: so the crossings lie on the crack) within reach of its patches,
    /// and its surface's beyond (the nearest patch's plane, with the right sign).
    double level(std::size_t tet, const std::array<double, 4>& bary, const Eigen::Vector3d& x)
    {
        if (m_surface.is_plane() || !m_reach.contains(x)) return m_surface.level(x);
        double phi = 0.0;
        for (std::size_t c = 0; c < 4; ++c) {
            const std::uint32_t n = m_model.elements()[tet].node[c];
            const auto [it, fresh] = m_node_level.try_emplace(n, 0.0);
            if (fresh) it->second = m_model.node_level(m_cut, n);
            phi += bary[c] * it->second;
        }
        return phi;
    }
    [[nodiscard]] bool in_crack(std::int64_t tet) const
    {
        return tet >= 0 && m_model.elements()[static_cast<std::size_t>(tet)].cut_index(m_cut) >= 0;
    }
    int add_point(std::size_t tet, const std::array<double, 4>& bary, int side, const Eigen::Vector3d& x, std::int32_t label)
    {
        m_points.push_back({tet, bary, side, x, label});
        return static_cast<int>(m_points.size()) - 1;
    }
    /// The region of the point `bary` of tetrahedron `tet`, except that where the point lies on
    /// the plane of one of its cuts (an edge or corner of that cut's crack faces) the side of that
    /// cut is taken from the first of `near` (tetrahedron and region of points beside it on the
    /// same face) that knows the cut, not from rounding.
    [[nodiscard]] unsigned region_near(std::size_t tet, const std::array<double, 4>& bary,
                                       std::initializer_list<std::pair<std::size_t, unsigned>> near) const
    {
        const XfemElement& el = m_model.elements()[tet];
        unsigned region = el.region_at(bary);
        for (std::size_t i = 0; i < el.cuts.size(); ++i) {
            double size = 0.0;
            for (const double phi : el.cuts[i].phi) size = std::max(size, std::abs(phi));
            if (std::abs(el.level_at(i, bary)) > 1e-9 * size) continue;
            for (const auto& [other, other_region] : near) {
                const int at = m_model.elements()[other].cut_index(el.cuts[i].id);
                if (at < 0) continue;
                region = (region & ~(1u << i)) | (((other_region >> at) & 1u) << i);
                break;
            }
        }
        return region;
    }
    /// Where a point not split by this cut goes: the tetrahedron across a segment's face (not cut
    /// by it), so both sides place it alike; the cut one, on side 0, where that face is the mesh's.
    /// `near`: a point beside it on the same face of any other cut (region_near).
    struct Placement {
        std::size_t tet = 0;
        std::array<double, 4> bary{};
        unsigned region = 0;
    };
    [[nodiscard]] Placement shared_place(std::size_t cut_tet, int face, const Eigen::Vector3d& x, std::pair<std::size_t, unsigned> near) const
    {
        const std::int32_t across = m_neighbours[cut_tet][static_cast<std::size_t>(face)];
        Placement p;
        p.tet = across < 0 ? cut_tet : static_cast<std::size_t>(across);
        p.bary = clamped(barycentric(m_model.mesh(), p.tet, x));
        p.region = region_near(p.tet, p.bary, {near});
        if (across < 0) p.region &= ~(1u << m_model.elements()[p.tet].cut_index(m_cut));
        return p;
    }
    void build_boundary();
    int crossing(int a, int b);
    /// The crossing's points, placed on first use.
    const std::array<int, 2>& ids(int crossing);
    int front(int inside, int outside);
    /// The end of R's boundary segment as a point of the face being walked (`near`: a point of that
    /// face); one per face side of any other cut through it.
    int corner_point(int segment, std::pair<std::size_t, unsigned> near);
    /// Chain nodes: crossings by index, fronts as -(index + 1).
    static int front_node(int f) { return -(f + 1); }
    /// Where a crack face's point lies in the cut's surface unrolled flat, which faces are
    /// triangulated in.
    [[nodiscard]] Eigen::Vector2d flat(const Eigen::Vector3d& x) const { return m_surface.unrolled(x); }
    /// Faces with their holes joined in (faces_with_holes: the material is on the left of every
    /// loop, so a hole runs clockwise); holes that cannot be placed count as open.
    std::vector<Loop> with_holes(std::vector<Loop> loops);
    /// Triangulates a crack face given round its boundary (each corner's point per side) on both sides.
    void emit(std::vector<std::array<int, 2>> ids, std::vector<Eigen::Vector3d> x, std::vector<Eigen::Vector3i>& triangles);

    const XfemModel& m_model;
    const std::vector<std::array<std::int32_t, 4>>& m_neighbours;
    int m_cut;
    const CutSurface& m_surface;
    std::vector<SurfacePoint>& m_points;
    std::vector<std::int32_t>* m_crack_of; ///< per triangle, whose crack face it is (-1: the object's surface); may be null
    Eigen::AlignedBox3d m_reach;                                ///< where the level is the model's
    std::unordered_map<std::uint32_t, double> m_node_level;    ///< the model's, by node, as asked for
    std::vector<double> m_point_level;                          ///< per point split() started with

    std::map<VertexEdge, int> m_crossing_of;
    std::vector<Crossing> m_crossings;
    std::vector<Front> m_fronts;
    std::map<int, int> m_next; ///< S's boundary inside R, material on its left: node -> the next node
    std::vector<Segment> m_segments;
    std::multimap<NodeEdge, int> m_leaving;               ///< R's boundary: its segments by start
    std::map<std::pair<std::size_t, int>, int> m_on_face; ///< (tet, face) -> its segment
    std::map<std::pair<NodeEdge, unsigned>, int> m_corner_points; ///< R's boundary vertices placed so far, by region
    /// The cut's crossings of the cut tetrahedra's edges, each moved a hundredth of the way to the
    /// centre of the cut's polygon in a tetrahedron there, and that tetrahedron: what a crack face
    /// takes inside it to follow the material (and the cut where it bends).
    std::vector<std::pair<Eigen::Vector3d, std::size_t>> m_crack_vertices;
    std::set<NodeEdge> m_crack_vertex_edges;
};

void Closer::build_boundary()
{
    const auto& elements = m_model.elements();
    const auto& nodes = m_model.mesh().nodes;
    for (std::size_t t = 0; t < elements.size(); ++t) {
        const int index = elements[t].cut_index(m_cut);
        if (index < 0) continue;
        const XfemElement& el = elements[t];
        const std::array<double, 4>& phi = el.cuts[static_cast<std::size_t>(index)].phi;
        // The cut's crossing of a tetrahedron edge, from its lower node: the same bits in every
        // tetrahedron around the edge.
        auto on_edge = [&](std::size_t a, std::size_t b) {
            if (el.node[a] > el.node[b]) std::swap(a, b);
            const double f = phi[a] / (phi[a] - phi[b]);
            return std::pair{NodeEdge{el.node[a], el.node[b]}, Eigen::Vector3d(nodes[el.node[a]] + f * (nodes[el.node[b]] - nodes[el.node[a]]))};
        };
        auto crossed = [&](std::size_t a, std::size_t b) { return (phi[a] < 0.0) != (phi[b] < 0.0); };
        Eigen::Vector3d centre = Eigen::Vector3d::Zero();
        std::vector<std::pair<NodeEdge, Eigen::Vector3d>> crossings; // at most four
        for (std::size_t a = 0; a < 4; ++a)
            for (std::size_t b = a + 1; b < 4; ++b)
                if (crossed(a, b)) {
                    crossings.push_back(on_edge(a, b));
                    centre += crossings.back().second;
                }
        if (crossings.size() < 3) continue;
        centre /= static_cast<double>(crossings.size());
        for (const auto& [edge, x] : crossings)
            if (m_crack_vertex_edges.insert(edge).second) m_crack_vertices.emplace_back(x + 0.01 * (centre - x), t);
        for (int face = 0; face < 4; ++face) {
            if (in_crack(m_neighbours[t][static_cast<std::size_t>(face)])) continue;
            std::vector<std::pair<NodeEdge, Eigen::Vector3d>> ends;
            for (std::size_t a = 0; a < 4; ++a)
                for (std::size_t b = a + 1; b < 4; ++b)
                    if (static_cast<int>(a) != face && static_cast<int>(b) != face && crossed(a, b)) ends.push_back(on_edge(a, b));
            if (ends.size() != 2) continue; // the cut through a corner of the face: no segment
            if ((ends[1].second - ends[0].second).cross(centre - ends[0].second).dot(m_model.crack_normal(m_cut, t)) < 0.0)
                std::swap(ends[0], ends[1]);
            const int s = static_cast<int>(m_segments.size());
            m_segments.push_back({ends[0].first, ends[1].first, ends[0].second, ends[1].second, t, face});
            m_leaving.emplace(ends[0].first, s);
            m_on_face[{t, face}] = s;
        }
    }
}

int Closer::crossing(int a, int b)
{
    const VertexEdge key = std::minmax(a, b);
    if (const auto it = m_crossing_of.find(key); it != m_crossing_of.end()) return it->second;
    const SurfacePoint va = m_points[static_cast<std::size_t>(key.first)]; // copies: m_points grows below
    const SurfacePoint vb = m_points[static_cast<std::size_t>(key.second)];
    double fa = m_point_level[static_cast<std::size_t>(key.first)], fb = m_point_level[static_cast<std::size_t>(key.second)];
    Eigen::Vector3d xa = va.rest_m, xb = vb.rest_m;
    Crossing c;
    c.x = xa + fa / (fa - fb) * (xb - xa);
    c.label = va.label;
    std::tie(c.tet, c.bary) = walk_to(m_model.mesh(), m_neighbours, va.tet, c.x);
    // A swept cut's level is linear only within a tetrahedron: a few steps of regula falsi put the
    // crossing on the crack where the edge spans several.
    for (int step = 0; step < 4 && !m_surface.is_plane(); ++step) {
        const double f = level(c.tet, c.bary, c.x);
        if (std::abs(f) <= 1e-9 * std::abs(fa - fb)) break;
        if ((f < 0.0) == (fa < 0.0)) {
            xa = c.x;
            fa = f;
        } else {
            xb = c.x;
            fb = f;
        }
        c.x = xa + fa / (fa - fb) * (xb - xa);
        std::tie(c.tet, c.bary) = walk_to(m_model.mesh(), m_neighbours, c.tet, c.x);
    }
    c.inside = in_crack(static_cast<std::int64_t>(c.tet));
    // On another cut's plane (an edge of that cut's crack faces) its side of that cut is the
    // edge's ends' (the face's side), not what rounding says.
    c.region = region_near(c.tet, c.bary, {{va.tet, static_cast<unsigned>(va.side)}, {vb.tet, static_cast<unsigned>(vb.side)}});
    m_crossings.push_back(c);
    return m_crossing_of[key] = static_cast<int>(m_crossings.size()) - 1;
}

const std::array<int, 2>& Closer::ids(int crossing)
{
    Crossing& c = m_crossings[static_cast<std::size_t>(crossing)];
    if (c.id[0] >= 0) return c.id;
    if (c.inside) {
        const unsigned bit = 1u << m_model.elements()[c.tet].cut_index(m_cut);
        c.id[0] = add_point(c.tet, c.bary, static_cast<int>(c.region & ~bit), c.x, c.label);
        c.id[1] = add_point(c.tet, c.bary, static_cast<int>(c.region | bit), c.x, c.label);
    } else {
        c.id[0] = c.id[1] = add_point(c.tet, c.bary, static_cast<int>(c.region), c.x, c.label);
    }
    return c.id;
}

int Closer::front(int inside, int outside)
{
    // Walk from the crossing in the crack towards the other, tetrahedron by tetrahedron, to the
    // face where the segment leaves the crack.
    const Eigen::Vector3d from = m_crossings[static_cast<std::size_t>(inside)].x, to = m_crossings[static_cast<std::size_t>(outside)].x;
    std::size_t t = m_crossings[static_cast<std::size_t>(inside)].tet;
    double entered = 0.0;
    for (int step = 0; step < 64; ++step) {
        const std::array<double, 4> b0 = barycentric(m_model.mesh(), t, from), b1 = barycentric(m_model.mesh(), t, to);
        double leaves = INFINITY;
        int face = -1;
        for (int c = 0; c < 4; ++c) {
            const double slope = b1[static_cast<std::size_t>(c)] - b0[static_cast<std::size_t>(c)];
            if (!(slope < 0.0)) continue;
            const double at = -b0[static_cast<std::size_t>(c)] / slope;
            if (at >= entered - 1e-9 && at < leaves) {
                leaves = at;
                face = c;
            }
        }
        if (face < 0) return -1;
        const std::int32_t across = m_neighbours[t][static_cast<std::size_t>(face)];
        if (in_crack(across)) {
            t = static_cast<std::size_t>(across);
            entered = leaves;
            continue;
        }
        const auto segment = m_on_face.find({t, face});
        if (segment == m_on_face.end()) return -1;
        Front f;
        if (leaves >= 1.0 - 1e-9) { // the crack ends on the triangle's edge: at the other crossing
            f.x = to;
            f.id = ids(outside)[0];
        } else {
            // Off the other end by at least a thousandth, so the front point and the split crossing
            // are not one place (a zero-length edge would stall the triangulation).
            f.x = from + std::max(leaves, 1e-3) * (to - from);
            const Crossing& beside = m_crossings[static_cast<std::size_t>(inside)];
            const Placement p = shared_place(t, face, f.x, {beside.tet, beside.region});
            f.id = add_point(p.tet, p.bary, static_cast<int>(p.region), f.x, beside.label);
        }
        f.segment = segment->second;
        const Segment& s = m_segments[static_cast<std::size_t>(f.segment)];
        f.along = (f.x - s.x_from).dot(s.x_to - s.x_from) / (s.x_to - s.x_from).squaredNorm();
        m_fronts.push_back(f);
        return static_cast<int>(m_fronts.size()) - 1;
    }
    return -1;
}

int Closer::corner_point(int segment, std::pair<std::size_t, unsigned> near)
{
    const Segment& s = m_segments[static_cast<std::size_t>(segment)];
    const Placement p = shared_place(s.tet, s.face, s.x_to, near);
    if (const auto it = m_corner_points.find({s.to, p.region}); it != m_corner_points.end()) return it->second;
    return m_corner_points[{s.to, p.region}] = add_point(p.tet, p.bary, static_cast<int>(p.region), s.x_to, 0);
}

void Closer::split(std::vector<Eigen::Vector3i>& triangles)
{
    // The triangles the cut crosses, and their crossings.
    // The level at every point within reach of the cut, and at those beyond only where a triangle
    // reaches in from them: elsewhere the surface stays whole (positive, whatever side), so a
    // cut far away costs no search of its patches and no crossings.
    m_point_level.assign(m_points.size(), NAN);
    for (std::size_t k = 0; k < m_points.size(); ++k)
        if (m_surface.is_plane() || m_reach.contains(m_points[k].rest_m)) m_point_level[k] = level(m_points[k].tet, m_points[k].bary, m_points[k].rest_m);
    for (const Eigen::Vector3i& t : triangles) {
        int beyond = 0;
        for (int a = 0; a < 3; ++a) beyond += std::isnan(m_point_level[static_cast<std::size_t>(t[a])]) ? 1 : 0;
        if (beyond == 0 || beyond == 3) continue;
        for (int a = 0; a < 3; ++a) {
            double& l = m_point_level[static_cast<std::size_t>(t[a])];
            if (std::isnan(l)) l = m_surface.level(m_points[static_cast<std::size_t>(t[a])].rest_m);
        }
    }
    for (double& l : m_point_level)
        if (std::isnan(l)) l = 1.0;
    std::vector<std::array<bool, 3>> positive(triangles.size());
    std::vector<std::array<int, 2>> cross(triangles.size(), {-1, -1});
    for (std::size_t i = 0; i < triangles.size(); ++i) {
        const Eigen::Vector3i& t = triangles[i];
        for (int a = 0; a < 3; ++a) positive[i][static_cast<std::size_t>(a)] = m_point_level[static_cast<std::size_t>(t[a])] >= 0.0;
        if (positive[i][0] == positive[i][1] && positive[i][1] == positive[i][2]) continue;
        for (int a = 0, k = 0; a < 3; ++a)
            if (positive[i][static_cast<std::size_t>(a)] != positive[i][static_cast<std::size_t>((a + 1) % 3)])
                cross[i][static_cast<std::size_t>(k++)] = crossing(t[a], t[(a + 1) % 3]);
    }
    // A loop of crossings that enters the crack anywhere is split all round (outside the crack each
    // piece keeps the crossing's one point): a triangle split beside one left whole would leave a
    // vertex in the middle of its edge.
    UnionFind loops(m_crossings.size());
    auto root = [&](int c) { return loops.find(static_cast<std::uint32_t>(c)); };
    for (const std::array<int, 2>& c : cross)
        if (c[0] >= 0) loops.unite(static_cast<std::uint32_t>(c[0]), static_cast<std::uint32_t>(c[1]));
    std::vector<bool> reaches_crack(m_crossings.size(), false);
    for (std::size_t c = 0; c < m_crossings.size(); ++c)
        if (m_crossings[c].inside) reaches_crack[root(static_cast<int>(c))] = true;

    std::vector<Eigen::Vector3i> kept;
    std::vector<std::int32_t> kept_crack; // each piece the crack face its triangle was, if any
    kept.reserve(triangles.size());
    for (std::size_t i = 0; i < triangles.size(); ++i) {
        const Eigen::Vector3i& t = triangles[i];
        if (cross[i][0] < 0 || !reaches_crack[root(cross[i][0])]) {
            kept.push_back(t);
            if (m_crack_of) kept_crack.push_back((*m_crack_of)[i]);
            continue;
        }
        const bool in0 = m_crossings[static_cast<std::size_t>(cross[i][0])].inside, in1 = m_crossings[static_cast<std::size_t>(cross[i][1])].inside;
        int f = -1;
        if (in0 != in1) {
            f = in0 ? front(cross[i][0], cross[i][1]) : front(cross[i][1], cross[i][0]);
            if (f < 0) ++counts.open_chains; // the crack's edge could not be found here: split without it, counted
        }
        // S's boundary in this triangle runs along n x (its outward normal), material on its left.
        const Eigen::Vector3d r0 = m_points[static_cast<std::size_t>(t[0])].rest_m;
        const Eigen::Vector3d outward =
            (m_points[static_cast<std::size_t>(t[1])].rest_m - r0).cross(m_points[static_cast<std::size_t>(t[2])].rest_m - r0);
        auto runs = [&](int from, int to) {
            const Crossing& a = m_crossings[static_cast<std::size_t>(from)];
            return (m_crossings[static_cast<std::size_t>(to)].x - a.x).dot(m_model.crack_normal(m_cut, a.tet).cross(outward)) > 0.0;
        };
        if (in0 && in1) {
            if (!runs(cross[i][1], cross[i][0]))
                m_next[cross[i][0]] = cross[i][1];
            else
                m_next[cross[i][1]] = cross[i][0];
        } else if (f >= 0) {
            const int inside = in0 ? cross[i][0] : cross[i][1], outside = in0 ? cross[i][1] : cross[i][0];
            if (runs(inside, outside)) { // leaving the crack at the front
                m_next[inside] = front_node(f);
            } else {
                m_fronts[static_cast<std::size_t>(f)].entering = true;
                m_next[front_node(f)] = inside;
            }
        }
        // Each side's piece, in the triangle's order: its corners and the crossings (the crack's
        // front point between them), fanned from a corner (off the plane's line).
        const bool front_inserted = f >= 0 && m_fronts[static_cast<std::size_t>(f)].id != ids(in0 ? cross[i][1] : cross[i][0])[0];
        for (int side = 0; side < 2; ++side) {
            std::vector<int> piece;
            std::vector<bool> on_plane;
            for (int a = 0, k = 0; a < 3; ++a) {
                const int b = (a + 1) % 3;
                if (positive[i][static_cast<std::size_t>(a)] == (side == 1)) {
                    piece.push_back(t[a]);
                    on_plane.push_back(false);
                }
                if (positive[i][static_cast<std::size_t>(a)] != positive[i][static_cast<std::size_t>(b)]) {
                    piece.push_back(ids(cross[i][static_cast<std::size_t>(k++)])[static_cast<std::size_t>(side)]);
                    on_plane.push_back(true);
                }
            }
            if (front_inserted) { // between the two crossings, which are neighbours round the piece
                std::size_t after = 0;
                while (!(on_plane[after] && on_plane[(after + 1) % piece.size()])) ++after;
                piece.insert(piece.begin() + static_cast<std::ptrdiff_t>(after + 1), m_fronts[static_cast<std::size_t>(f)].id);
                on_plane.insert(on_plane.begin() + static_cast<std::ptrdiff_t>(after + 1), true);
            }
            const auto corner = static_cast<std::size_t>(std::find(on_plane.begin(), on_plane.end(), false) - on_plane.begin());
            const std::size_t m = piece.size();
            for (std::size_t k = 1; k + 1 < m; ++k) kept.emplace_back(piece[corner], piece[(corner + k) % m], piece[(corner + k + 1) % m]);
        }
        if (m_crack_of) kept_crack.resize(kept.size(), (*m_crack_of)[i]);
    }
    triangles = std::move(kept);
    if (m_crack_of) *m_crack_of = std::move(kept_crack);
}

void Closer::emit(std::vector<std::array<int, 2>> ids, std::vector<Eigen::Vector3d> x, std::vector<Eigen::Vector3i>& triangles)
{
    std::vector<Eigen::Vector2d> in_plane;
    in_plane.reserve(x.size());
    for (const Eigen::Vector3d& p : x) in_plane.push_back(flat(p));
    // Corners on the front are one point for both sides. A triangle with only such corners would
    // be the same on both sides, glued to itself: it is left out (the crack does not open there).
    // A diagonal between two of them with split corners on both its sides would glue the two
    // faces along it: the triangulation avoids those, and any left are split at their middle.
    std::vector<bool> shared(ids.size());
    for (std::size_t k = 0; k < ids.size(); ++k) shared[k] = ids[k][0] == ids[k][1];
    std::vector<std::array<int, 3>> faces;
    for (const std::array<int, 3>& f : triangulate_polygon(in_plane, shared))
        if (!shared[static_cast<std::size_t>(f[0])] || !shared[static_cast<std::size_t>(f[1])] || !shared[static_cast<std::size_t>(f[2])]) faces.push_back(f);
    // The cut's vertices inside the face (m_crack_vertices) are added: where a swept cut bends,
    // triangles across its face would cut through the material; and a face spanned by its rim
    // alone is drawn flat however the material inside it bends, and two walls pressed together
    // would touch only at their rims (piece contact presses vertices into faces). Each is moved a
    // hundredth of the way into a tetrahedron: on the mesh's edges, a later cut along a row of
    // nodes passed exactly through them (its level 0 at a vertex) and its crossings there did not
    // join into faces. (The polygons' centres alone made walls that sank into each other.)
    const std::size_t boundary = ids.size();
    for (const auto& [point, tet] : m_crack_vertices) {
        const Eigen::Vector2d unrolled = flat(point);
        const Location holder = locate(in_plane, faces, unrolled);
        if (holder.triangle < 0) continue;
        insert_point(in_plane, faces, holder, unrolled, boundary);
        const std::array<double, 4> bary = clamped(barycentric(m_model.mesh(), tet, point));
        const unsigned region = m_model.elements()[tet].region_at(bary);
        const unsigned bit = 1u << m_model.elements()[tet].cut_index(m_cut);
        ids.push_back({add_point(tet, bary, static_cast<int>(region & ~bit), point, 0), add_point(tet, bary, static_cast<int>(region | bit), point, 0)});
        x.push_back(point);
        shared.push_back(false);
    }
    std::map<std::pair<int, int>, std::vector<std::size_t>> glued; // shared-shared edge -> the faces using it
    for (std::size_t k = 0; k < faces.size(); ++k)
        for (int e = 0; e < 3; ++e) {
            const int a = faces[k][static_cast<std::size_t>(e)], b = faces[k][static_cast<std::size_t>((e + 1) % 3)];
            if (shared[static_cast<std::size_t>(a)] && shared[static_cast<std::size_t>(b)]) glued[std::minmax(a, b)].push_back(k);
        }
    for (const auto& [edge, users] : glued) {
        if (users.size() != 2) continue; // a front edge: one face, split corner opposite
        const Eigen::Vector3d middle = 0.5 * (x[static_cast<std::size_t>(edge.first)] + x[static_cast<std::size_t>(edge.second)]);
        // Walk to it from a split corner of a face beside it (in a cut tetrahedron), whose sides of
        // other cuts it shares.
        SurfacePoint beside;
        for (int c : faces[users[0]])
            if (!shared[static_cast<std::size_t>(c)]) beside = m_points[static_cast<std::size_t>(ids[static_cast<std::size_t>(c)][0])];
        const auto [tet, bary] = walk_to(m_model.mesh(), m_neighbours, beside.tet, middle);
        if (!in_crack(static_cast<std::int64_t>(tet))) continue;
        const unsigned region = region_near(tet, bary, {{beside.tet, static_cast<unsigned>(beside.side)}});
        const unsigned bit = 1u << m_model.elements()[tet].cut_index(m_cut);
        const int m = static_cast<int>(ids.size());
        ids.push_back({add_point(tet, bary, static_cast<int>(region & ~bit), middle, 0), add_point(tet, bary, static_cast<int>(region | bit), middle, 0)});
        x.push_back(middle);
        for (std::size_t k : users) {
            std::array<int, 3> f = faces[k];
            int e = 0;
            while (std::pair<int, int>(std::minmax(f[static_cast<std::size_t>(e)], f[static_cast<std::size_t>((e + 1) % 3)])) != edge) ++e;
            const int a = f[static_cast<std::size_t>(e)], b = f[static_cast<std::size_t>((e + 1) % 3)], c = f[static_cast<std::size_t>((e + 2) % 3)];
            faces[k] = {a, m, c};
            faces.push_back({m, b, c});
        }
    }
    // Counter-clockwise in the unrolled surface faces its positive side: out of the negative side (0).
    for (const std::array<int, 3>& f : faces) {
        auto id = [&](int k, int side) { return ids[static_cast<std::size_t>(f[static_cast<std::size_t>(k)])][static_cast<std::size_t>(side)]; };
        triangles.emplace_back(id(0, 0), id(1, 0), id(2, 0));
        triangles.emplace_back(id(0, 1), id(2, 1), id(1, 1));
        if (m_crack_of) m_crack_of->insert(m_crack_of->end(), 2, m_cut);
    }
}

void Closer::fill(std::vector<Eigen::Vector3i>& triangles)
{
    auto add_node = [&](int node, std::vector<std::array<int, 2>>& ids, std::vector<Eigen::Vector3d>& x) {
        if (node >= 0) {
            ids.push_back(this->ids(node));
            x.push_back(m_crossings[static_cast<std::size_t>(node)].x);
        } else {
            const Front& f = m_fronts[static_cast<std::size_t>(-node - 1)];
            ids.push_back({f.id, f.id});
            x.push_back(f.x);
        }
    };
    // The runs of S's boundary inside R, each from an entering front to a leaving one.
    std::vector<std::vector<int>> chains;
    std::map<int, bool> visited;
    for (std::size_t f = 0; f < m_fronts.size(); ++f) {
        if (!m_fronts[f].entering) continue;
        std::vector<int> chain{front_node(static_cast<int>(f))};
        for (auto it = m_next.find(chain.back()); it != m_next.end() && chain.size() <= m_next.size(); it = m_next.find(chain.back())) {
            chain.push_back(it->second);
            visited[it->second] = true;
            if (it->second < 0) break;
        }
        if (chain.back() >= 0 || chain.size() < 2) {
            ++counts.open_chains;
            continue;
        }
        m_fronts[f].chain = m_fronts[static_cast<std::size_t>(-chain.back() - 1)].chain = static_cast<int>(chains.size());
        chains.push_back(std::move(chain));
    }
    std::vector<Loop> loops;
    // Loops of S's boundary wholly inside R: a cut through the object there (or a hole in a face).
    for (const auto& [start, unused] : m_next) {
        if (start < 0 || visited[start]) continue;
        std::vector<int> loop{start};
        visited[start] = true;
        bool closed = false;
        for (auto it = m_next.find(start); it != m_next.end() && it->second >= 0; it = m_next.find(loop.back())) {
            if (it->second == start) {
                closed = true;
                break;
            }
            if (visited[it->second]) break;
            visited[it->second] = true;
            loop.push_back(it->second);
        }
        if (!closed || loop.size() < 3) {
            ++counts.open_chains;
            continue;
        }
        Loop face;
        for (int node : loop) add_node(node, face.ids, face.x);
        loops.push_back(std::move(face));
    }
    // Faces with a front: a chain, then R's boundary from where it leaves the crack to the next
    // entering front along it, that front's chain, and so on round to the first.
    std::vector<bool> used(chains.size(), false);
    for (std::size_t first = 0; first < chains.size(); ++first) {
        if (used[first]) continue;
        std::vector<std::array<int, 2>> ids;
        std::vector<Eigen::Vector3d> x;
        std::size_t c = first;
        bool closed = false;
        for (std::size_t guard = 0; guard <= chains.size(); ++guard) {
            used[c] = true;
            for (int node : chains[c]) add_node(node, ids, x);
            const Front& out = m_fronts[static_cast<std::size_t>(-chains[c].back() - 1)];
            int segment = out.segment;
            double after = out.along;
            int next = -1;
            for (std::size_t steps = 0; steps <= m_segments.size() && next < 0; ++steps) {
                double nearest = INFINITY;
                // Strictly past where it left: a front entering at that very point belongs to the
                // piece across another cut through it (two crack faces on each other at rest).
                for (const Front& f : m_fronts)
                    if (f.entering && f.chain >= 0 && f.segment == segment && f.along > after && f.along < nearest) {
                        nearest = f.along;
                        next = f.chain;
                    }
                if (next >= 0) break;
                const SurfacePoint& left_at = m_points[static_cast<std::size_t>(out.id)];
                const int corner = corner_point(segment, {left_at.tet, static_cast<unsigned>(left_at.side)});
                ids.push_back({corner, corner});
                x.push_back(m_segments[static_cast<std::size_t>(segment)].x_to);
                const auto leaving = m_leaving.find(m_segments[static_cast<std::size_t>(segment)].to);
                if (leaving == m_leaving.end()) break;
                segment = leaving->second;
                after = -INFINITY;
            }
            if (next < 0) break;
            if (static_cast<std::size_t>(next) == first) {
                closed = true;
                break;
            }
            if (used[static_cast<std::size_t>(next)]) break;
            c = static_cast<std::size_t>(next);
        }
        if (!closed || ids.size() < 3) {
            ++counts.open_chains;
            continue;
        }
        loops.push_back({std::move(ids), std::move(x), true});
    }
    for (Loop& face : with_holes(std::move(loops))) {
        emit(std::move(face.ids), std::move(face.x), triangles);
        ++counts.faces;
        counts.slit_faces += face.slit ? 1 : 0;
    }
}

std::vector<Loop> Closer::with_holes(std::vector<Loop> loops)
{
    std::vector<std::vector<Eigen::Vector2d>> in_plane;
    for (const Loop& loop : loops) {
        in_plane.emplace_back();
        for (const Eigen::Vector3d& p : loop.x) in_plane.back().push_back(flat(p));
    }
    std::vector<Loop> out;
    for (const std::vector<LoopCorner>& face : faces_with_holes(in_plane, counts.open_chains)) {
        Loop merged;
        merged.slit = loops[face.front().loop].slit;
        for (const LoopCorner& c : face) {
            merged.ids.push_back(loops[c.loop].ids[c.corner]);
            merged.x.push_back(loops[c.loop].x[c.corner]);
        }
        out.push_back(std::move(merged));
    }
    return out;
}

} // namespace

CutClosure::CutClosure(const XfemModel& model) : m_model(model), m_neighbours(face_neighbours(model.mesh())) {}

ClosureCounts CutClosure::close(int cut, std::vector<SurfacePoint>& points, std::vector<Eigen::Vector3i>& triangles,
                                std::vector<std::int32_t>* crack_of) const
{
    if (crack_of) crack_of->resize(triangles.size(), -1);
    Closer closer(m_model, m_neighbours, cut, points, crack_of);
    closer.split(triangles);
    closer.fill(triangles);
    return closer.counts;
}

} // namespace vox::isxfem
