#include "contact/contact_patch.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>

namespace vox::contact {
namespace {

/// The patch's triangles as they are subdivided: positions, whether each point is held (on the
/// patch's border), and a normal to orient the fine triangles' by.
struct LocalMesh {
    std::vector<Eigen::Vector3d> positions, reference_normals;
    std::vector<unsigned char> held;
    std::vector<Eigen::Vector3i> triangles;
};

/// One edge of a triangle, its ends in order (a < b) and the triangle's third corner.
struct HalfEdge {
    int a, b, opposite;
};

/// The edges of `triangles`, each with the corners opposite it (one on a border, two inside),
/// sorted by their ends.
std::vector<HalfEdge> half_edges(const std::vector<Eigen::Vector3i>& triangles)
{
    std::vector<HalfEdge> out;
    out.reserve(3 * triangles.size());
    for (const Eigen::Vector3i& t : triangles)
        for (int k = 0; k < 3; ++k) out.push_back({std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3]), t[(k + 2) % 3]});
    std::sort(out.begin(), out.end(), [](const HalfEdge& x, const HalfEdge& y) { return x.a < y.a || (x.a == y.a && x.b < y.b); });
    return out;
}

/// One step of Loop subdivision: each edge gets a point (3/8 of its ends and 1/8 of the two
/// corners across it; the middle of a border edge, held), each point inside moves to
/// (1 - n beta) v + beta (sum of its n neighbours) with Warren's beta, held points stay, and each
/// triangle becomes four. The border stays where the snapshot's surface has it, so the patch
/// meets the surface around it without a crack.
LocalMesh loop_subdivide(const LocalMesh& m)
{
    const std::vector<HalfEdge> edges = half_edges(m.triangles);
    const std::size_t n = m.positions.size();
    LocalMesh out;
    out.positions = m.positions;
    out.reference_normals = m.reference_normals;
    out.held = m.held;
    std::vector<std::vector<int>> neighbours(n);
    struct Odd {
        int a, b, index;
    };
    std::vector<Odd> odd;
    for (std::size_t k = 0; k < edges.size();) {
        std::size_t end = k;
        while (end < edges.size() && edges[end].a == edges[k].a && edges[end].b == edges[k].b) ++end;
        const HalfEdge& e = edges[k];
        const Eigen::Vector3d &pa = m.positions[static_cast<std::size_t>(e.a)], &pb = m.positions[static_cast<std::size_t>(e.b)];
        const bool inside = end - k == 2;
        out.positions.push_back(inside ? Eigen::Vector3d(0.375 * (pa + pb) + 0.125 * (m.positions[static_cast<std::size_t>(e.opposite)] +
                                                                                        m.positions[static_cast<std::size_t>(edges[k + 1].opposite)]))
                                       : Eigen::Vector3d(0.5 * (pa + pb)));
        out.reference_normals.push_back((m.reference_normals[static_cast<std::size_t>(e.a)] + m.reference_normals[static_cast<std::size_t>(e.b)]).normalized());
        out.held.push_back(inside ? 0 : 1);
        odd.push_back({e.a, e.b, static_cast<int>(out.positions.size() - 1)});
        neighbours[static_cast<std::size_t>(e.a)].push_back(e.b);
        neighbours[static_cast<std::size_t>(e.b)].push_back(e.a);
        k = end;
    }
    for (std::size_t v = 0; v < n; ++v) {
        if (m.held[v] || neighbours[v].empty()) continue;
        const double valence = static_cast<double>(neighbours[v].size());
        const double beta = neighbours[v].size() == 3 ? 3.0 / 16.0 : 3.0 / (8.0 * valence);
        Eigen::Vector3d sum = Eigen::Vector3d::Zero();
        for (int w : neighbours[v]) sum += m.positions[static_cast<std::size_t>(w)];
        out.positions[v] = (1.0 - valence * beta) * m.positions[v] + beta * sum;
    }
    auto odd_of = [&](int a, int b) {
        const int lo = std::min(a, b), hi = std::max(a, b);
        const auto it = std::lower_bound(odd.begin(), odd.end(), Odd{lo, hi, 0},
                                         [](const Odd& x, const Odd& y) { return x.a < y.a || (x.a == y.a && x.b < y.b); });
        return it->index;
    };
    out.triangles.reserve(4 * m.triangles.size());
    for (const Eigen::Vector3i& t : m.triangles) {
        const int m01 = odd_of(t[0], t[1]), m12 = odd_of(t[1], t[2]), m20 = odd_of(t[2], t[0]);
        out.triangles.emplace_back(t[0], m01, m20);
        out.triangles.emplace_back(t[1], m12, m01);
        out.triangles.emplace_back(t[2], m20, m12);
        out.triangles.emplace_back(m01, m12, m20);
    }
    return out;
}

/// The springs' displacement under `load` (per free point, N), by conjugate gradients (symmetric,
/// positive definite: every point has a home spring).
Eigen::VectorXd spring_give(const PatchLayer& patch, std::span<const double> load)
{
    const auto n = static_cast<Eigen::Index>(patch.free);
    const Eigen::Map<const Eigen::VectorXd> b(load.data(), n);
    Eigen::VectorXd x = Eigen::VectorXd::Zero(n), r = b, p = Eigen::VectorXd::Zero(n + 1), ap(n); // p[n] = 0: the padding's
    p.head(n) = r;
    double rr = r.squaredNorm();
    for (int k = 0; k < 10 * n && rr > 1e-28 * b.squaredNorm(); ++k) {
        for (Eigen::Index i = 0; i < n; ++i)
            ap[i] = patch.spring_product(static_cast<std::size_t>(i), p, patch.spring_diagonal_n_per_mm[static_cast<std::size_t>(i)]);
        const double alpha = rr / p.head(n).dot(ap);
        x += alpha * p.head(n);
        r -= alpha * ap;
        const double next = r.squaredNorm();
        p.head(n) = r + (next / rr) * p.head(n);
        rr = next;
    }
    return x;
}

} // namespace

double patch_compliance(const PatchLayer& patch, std::span<const double> load)
{
    const auto n = static_cast<Eigen::Index>(patch.free);
    const Eigen::Map<const Eigen::VectorXd> b(load.data(), n);
    const double total = b.sum();
    if (n == 0 || !(total > 0.0)) return 0.0;
    return b.dot(spring_give(patch, load)) / (total * total);
}

bool build_patch(SurfacePoints& s, const PlacedShape& tool, const ContactParameters& contact, double compliance_mm_per_n,
                 const PatchSettings& settings)
{
    PatchLayer& patch = s.patch;
    patch.count = patch.free = 0;
    s.replaced.clear();
    if (!(compliance_mm_per_n > 0.0) || settings.levels < 0 || s.count == 0 || s.triangles.empty() || !s.stiffness_n_per_mm.empty())
        return false;
    const std::span<const Eigen::Vector3d> positions(s.positions_mm.data(), s.count), normals(s.normals.data(), s.count);
    const std::span<const double> areas(s.areas_mm2.data(), s.count);
    const ContactResult touching = penalty_contact(tool, contact, positions, areas, normals);
    if (touching.points.empty()) return false;
    // Around the contact's load-weighted middle, as far as it reaches and then settings.reach_mm.
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    double load = 0.0;
    for (const PointContact& c : touching.points) {
        centre += c.force_n.norm() * positions[c.point];
        load += c.force_n.norm();
    }
    if (!(load > 0.0)) return false;
    centre /= load;
    double radius = 0.0;
    for (const PointContact& c : touching.points) radius = std::max(radius, (positions[c.point] - centre).norm());
    radius += settings.reach_mm;

    // The snapshot's triangles wholly within it, on their own points.
    std::vector<int> local(s.count, -1);
    LocalMesh mesh;
    std::vector<std::size_t> global;
    for (const Eigen::Vector3i& t : s.triangles) {
        bool within = true;
        for (int c = 0; c < 3; ++c) within = within && (positions[static_cast<std::size_t>(t[c])] - centre).norm() <= radius;
        if (!within) continue;
        Eigen::Vector3i lt;
        for (int c = 0; c < 3; ++c) {
            int& l = local[static_cast<std::size_t>(t[c])];
            if (l < 0) {
                l = static_cast<int>(global.size());
                global.push_back(static_cast<std::size_t>(t[c]));
                mesh.positions.push_back(positions[static_cast<std::size_t>(t[c])]);
                mesh.reference_normals.push_back(normals[static_cast<std::size_t>(t[c])]);
            }
            lt[c] = l;
        }
        mesh.triangles.push_back(lt);
    }
    // A point on an edge with one triangle (the patch's outline, or the snapshot's) is held.
    mesh.held.assign(mesh.positions.size(), 0);
    const std::vector<HalfEdge> edges = half_edges(mesh.triangles);
    for (std::size_t k = 0; k < edges.size();) {
        std::size_t end = k;
        while (end < edges.size() && edges[end].a == edges[k].a && edges[end].b == edges[k].b) ++end;
        if (end - k != 2) mesh.held[static_cast<std::size_t>(edges[k].a)] = mesh.held[static_cast<std::size_t>(edges[k].b)] = 1;
        k = end;
    }
    const std::size_t coarse_points = mesh.positions.size();
    // None where the snapshot's own points there pass the tick's budget (a large tool on a fine
    // surface): the rigid snapshot serves.
    if (coarse_points > settings.max_points || std::count(mesh.held.begin(), mesh.held.end(), 0) == 0) return false;
    // As many levels as asked, fewer if the patch would hold more than max_points (each level
    // multiplies the points by about four).
    int level = 0;
    for (std::size_t points = coarse_points; level < settings.levels && 4 * points <= settings.max_points; points *= 4) ++level;
    for (int k = 0; k < level; ++k) mesh = loop_subdivide(mesh);

    // Free points first, then the held ones.
    const std::size_t n = mesh.positions.size();
    std::vector<std::uint32_t> order(n);
    std::size_t free = 0;
    for (std::size_t v = 0; v < n; ++v)
        if (!mesh.held[v]) order[v] = static_cast<std::uint32_t>(free++);
    std::size_t next = free;
    for (std::size_t v = 0; v < n; ++v)
        if (mesh.held[v]) order[v] = static_cast<std::uint32_t>(next++);
    patch.count = n;
    patch.free = free;
    patch.level = level;
    patch.positions_mm.assign(n, Eigen::Vector3d::Zero());
    patch.normals.assign(n, Eigen::Vector3d::Zero());
    patch.areas_mm2.assign(n, 0.0);
    patch.triangles.clear();
    for (std::size_t v = 0; v < n; ++v) patch.positions_mm[order[v]] = mesh.positions[v];
    for (const Eigen::Vector3i& t : mesh.triangles) {
        const Eigen::Vector3i ft(static_cast<int>(order[static_cast<std::size_t>(t[0])]), static_cast<int>(order[static_cast<std::size_t>(t[1])]),
                                 static_cast<int>(order[static_cast<std::size_t>(t[2])]));
        patch.triangles.push_back(ft);
        const Eigen::Vector3d& a = patch.positions_mm[static_cast<std::size_t>(ft[0])];
        const Eigen::Vector3d cross = (patch.positions_mm[static_cast<std::size_t>(ft[1])] - a).cross(patch.positions_mm[static_cast<std::size_t>(ft[2])] - a);
        for (int c = 0; c < 3; ++c) {
            patch.normals[static_cast<std::size_t>(ft[c])] += cross; // area-weighted (twice the area)
            patch.areas_mm2[static_cast<std::size_t>(ft[c])] += cross.norm() / 6.0;
        }
    }
    // The fine triangles' normals, facing the way the snapshot's do.
    for (std::size_t v = 0; v < n; ++v) {
        Eigen::Vector3d& normal = patch.normals[order[v]];
        const Eigen::Vector3d& reference = mesh.reference_normals[v];
        normal = normal.squaredNorm() > 0.0 ? normal.normalized() : reference;
        if (normal.dot(reference) < 0.0) normal = -normal;
    }
    // The mesh springs: per free point, how many (its diagonal) and which of them reach another
    // free point, and those edges once.
    std::vector<std::uint32_t> degree(free, 0), free_degree(free, 0);
    patch.free_edges.clear();
    patch.longest_free_edge_mm = 0.0;
    for (const Eigen::Vector2i& e : surface_edges(patch.triangles)) {
        for (int end : {e[0], e[1]})
            if (static_cast<std::size_t>(end) < free) ++degree[static_cast<std::size_t>(end)];
        if (static_cast<std::size_t>(e[1]) >= free) continue; // e[0] < e[1]: a held end
        patch.free_edges.push_back(e);
        ++free_degree[static_cast<std::size_t>(e[0])];
        ++free_degree[static_cast<std::size_t>(e[1])];
        patch.longest_free_edge_mm = std::max(
            patch.longest_free_edge_mm, (patch.positions_mm[static_cast<std::size_t>(e[1])] - patch.positions_mm[static_cast<std::size_t>(e[0])]).norm());
    }
    patch.neighbour_slots = free > 0 ? *std::max_element(free_degree.begin(), free_degree.end()) : 0;
    patch.free_neighbours.assign(free * patch.neighbour_slots, static_cast<std::uint32_t>(free));
    std::fill(free_degree.begin(), free_degree.end(), 0);
    for (const Eigen::Vector2i& e : patch.free_edges)
        for (int k = 0; k < 2; ++k) {
            const auto i = static_cast<std::size_t>(e[k]);
            patch.free_neighbours[i * patch.neighbour_slots + free_degree[i]++] = static_cast<std::uint32_t>(e[1 - k]);
        }

    // The load the tool presses each free point with now: the preload, and the load the springs
    // are scaled under.
    patch.preload_n.assign(free, 0.0);
    const ContactResult pressed = penalty_contact(tool, contact, std::span<const Eigen::Vector3d>(patch.positions_mm.data(), free),
                                                  std::span<const double>(patch.areas_mm2.data(), free),
                                                  std::span<const Eigen::Vector3d>(patch.normals.data(), free));
    for (const PointContact& c : pressed.points) patch.preload_n[c.point] = std::max(0.0, -c.force_n.dot(patch.normals[c.point]));
    const double total_preload = std::accumulate(patch.preload_n.begin(), patch.preload_n.end(), 0.0);
    if (!(total_preload > 0.0)) { // the contact is on the border only
        patch.count = patch.free = 0;
        return false;
    }
    // Springs at kappa = 1 (see the header), then kappa scaled to the FEM's compliance.
    const double l = settings.decay_mm;
    patch.mesh_n_per_mm = l * l / std::sqrt(3.0);
    patch.spring_diagonal_n_per_mm.assign(free, 0.0);
    for (std::size_t i = 0; i < free; ++i) patch.spring_diagonal_n_per_mm[i] = patch.areas_mm2[i] + patch.mesh_n_per_mm * degree[i];
    const Eigen::VectorXd give = spring_give(patch, patch.preload_n); // at kappa = 1
    const double kappa = Eigen::Map<const Eigen::VectorXd>(patch.preload_n.data(), static_cast<Eigen::Index>(free)).dot(give) /
                         (total_preload * total_preload) / compliance_mm_per_n;
    for (double& k : patch.spring_diagonal_n_per_mm) k *= kappa;
    patch.mesh_n_per_mm *= kappa;
    patch.compliance_mm_per_n = compliance_mm_per_n;
    patch.preload_give_mm.assign(give.data(), give.data() + free);
    for (double& g : patch.preload_give_mm) g /= kappa;

    // The snapshot points the patch stands in for: its free points that were snapshot points.
    s.replaced.assign(s.count, 0);
    patch.snapshot_point.assign(free, -1);
    for (std::size_t v = 0; v < coarse_points; ++v) {
        if (mesh.held[v]) continue;
        s.replaced[global[v]] = 1;
        patch.snapshot_point[order[v]] = static_cast<std::int32_t>(global[v]);
    }
    return true;
}

ContactPatchState::ContactPatchState(std::size_t capacity)
    : m_displaced(capacity), m_u(capacity, 0.0), m_distance(capacity, 0.0), m_signed(capacity, 0.0), m_diagonal(capacity, 1.0),
      m_inverse(capacity, 1.0), m_r(capacity, 0.0), m_p(capacity, 0.0), m_ap(capacity, 0.0), m_carried(capacity, 0.0), m_measured_u(capacity, 0.0), m_rim(capacity, 0)
{
    m_displaced.edges.reserve(3 * capacity + 16); // a triangulated patch has about three edges a point
}

double ContactPatchState::max_displacement_mm() const noexcept
{
    double out = 0.0;
    for (std::size_t i = 0; i < m_displaced.count; ++i) out = std::max(out, std::abs(m_u[i]));
    return out;
}

void ContactPatchState::take_over(const PatchLayer& p, double k_per_area) noexcept
{
    // The normal load the new patch's points carry undisplaced (the rigid snapshot's), and how
    // fast it falls as they give along the preload's shape (pressed points only: linear in beta).
    double rigid = 0.0, per_beta = 0.0;
    for (std::size_t i = 0; i < p.free; ++i)
        if (m_distance[i] > 0.0) {
            rigid += k_per_area * p.areas_mm2[i] * m_distance[i];
            per_beta += k_per_area * p.areas_mm2[i] * p.preload_give_mm[i];
        }
    // Displaced by beta times that shape so the load is the last patch's: the FEM behind the new
    // snapshot has not yet taken all the load the layer held. Never the other way (beta < 0, the
    // layer bulging out to hold a load the FEM has dropped, as under a tool lifting off faster
    // than the surface follows it): the FEM's own lag is the physics there. A patch after none
    // (the tool's first contact there) takes the snapshot's points' load as is.
    const double beta = m_had_patch && per_beta > 0.0 ? std::clamp((rigid - m_load_n) / per_beta, 0.0, 2.0) : 0.0;
    // The carried load makes that the layer's equilibrium: per point, its contact less the
    // springs' pull, (1 + beta) times the preload (the springs give the preload's shape under it).
    for (std::size_t i = 0; i < p.free; ++i) {
        m_u[i] = beta * p.preload_give_mm[i];
        const double depth = m_distance[i] - m_u[i];
        m_carried[i] = (depth > 0.0 ? k_per_area * p.areas_mm2[i] * depth : 0.0) - (1.0 + beta) * p.preload_n[i];
    }
}

ContactTotals ContactPatchState::step(const PlacedShape& tool, const ContactParameters& contact, const SurfacePoints& snapshot, double dt_s) noexcept
{
    const PatchLayer& p = snapshot.patch;
    if (p.free == 0 || p.free >= m_displaced.capacity() || p.free_edges.size() > m_displaced.edges.capacity()) { // one more: the padding's zero
        m_displaced.count = 0;
        m_had_patch = false;
        m_load_n = m_give_mm = 0.0;
        return {};
    }
    const std::size_t n = p.free;
    const Eigen::AlignedBox3d reach = tool.world_bounds(contact.margin_mm);
    const double k_per_area = contact.stiffness_n_per_mm / 100.0; // per mm^2
    const bool fresh = snapshot.t_s != m_patch_t_s || m_displaced.count != n;
    if (fresh) { // a new patch, on the new snapshot
        m_patch_t_s = snapshot.t_s;
        m_displaced.count = n;
        std::copy_n(p.normals.begin(), n, m_displaced.normals.begin());
        std::copy_n(p.areas_mm2.begin(), n, m_displaced.areas_mm2.begin());
        std::fill_n(m_u.begin(), n + 1, 0.0);
        m_p[n] = 0.0; // the padding's
    }
    // The tool's distance, its frame's turn taken once for the tick's few hundred points.
    const Eigen::Matrix3d to_tool = tool.orientation.conjugate().toRotationMatrix();
    auto distance = [&](const Eigen::Vector3d& x) { return tool.shape->signed_distance(to_tool * (x - tool.position)); };
    // Each point's depth in the pushing shape where it is now, taken back to u = 0 along its
    // normal (the depth falls by what the point gives): the linearised contact of this tick.
    auto measure = [&](std::size_t i) {
        const Eigen::Vector3d x = p.positions_mm[i] - m_u[i] * p.normals[i];
        m_distance[i] = reach.contains(x) ? contact.margin_mm - distance(x) + m_u[i] : -INFINITY;
        m_measured_u[i] = m_u[i];
    };
    // The layer under this tick's linearised contact, (K + C) u = C D - preload - carried (C: each
    // pressed point's contact stiffness; D: its depth at u = 0), solved by a few conjugate-gradient
    // iterations from the last tick's u, Jacobi preconditioned: the warm start is close (a tick
    // moves the tool micrometres), and a patch converges in about l / h iterations from rest.
    // Per point: its diagonal, and its residual at the warm start. The carried load fades as the
    // FEM takes it up, over k_handoff_s.
    const double fade = std::exp(-(dt_s > 0.0 ? dt_s : 1e-3) / k_handoff_s);
    double rz = 0.0, rr = 0.0;
    auto set_row = [&](std::size_t i) {
        const double k_contact = k_per_area * p.areas_mm2[i];
        const bool pressed = m_distance[i] - m_u[i] > 0.0;
        m_carried[i] *= fade;
        m_diagonal[i] = p.spring_diagonal_n_per_mm[i] + (pressed ? k_contact : 0.0);
        m_inverse[i] = 1.0 / m_diagonal[i];
        const double b = (pressed ? k_contact * m_distance[i] : 0.0) - p.preload_n[i] - m_carried[i];
        m_r[i] = b - p.spring_product(i, m_u, m_diagonal[i]);
        m_p[i] = 0.0; // the first direction is the preconditioned residual alone (beta = 0 below)
        rz += m_r[i] * m_r[i] * m_inverse[i];
        rr += m_r[i] * m_r[i];
    };
    if (fresh) { // the new patch starts where the last left off, from every point's depth
        for (std::size_t i = 0; i < n; ++i) measure(i);
        take_over(p, k_per_area);
        for (std::size_t i = 0; i < n; ++i) set_row(i);
    } else {
        for (std::size_t i = 0; i < n; ++i) {
            measure(i);
            set_row(i);
        }
    }
    // Until the points' unbalanced forces are far below what a hand feels (k_residual_n in all).
    // Each iteration: the new direction; its product (each point gathering its neighbours, so no
    // point is written twice) and p . A p; the step.
    double beta = 0.0;
    for (int it = 0; it < k_iterations && rr > k_residual_n * k_residual_n; ++it) {
        for (std::size_t i = 0; i < n; ++i) m_p[i] = m_r[i] * m_inverse[i] + beta * m_p[i];
        double pap = 0.0;
        for (std::size_t i = 0; i < n; ++i) {
            m_ap[i] = p.spring_product(i, m_p, m_diagonal[i]);
            pap += m_ap[i] * m_p[i];
        }
        if (!(pap > 0.0)) break;
        const double alpha = rz / pap;
        double next = 0.0;
        rr = 0.0;
        for (std::size_t i = 0; i < n; ++i) {
            m_u[i] += alpha * m_p[i];
            m_r[i] -= alpha * m_ap[i];
            next += m_r[i] * m_r[i] * m_inverse[i];
            rr += m_r[i] * m_r[i];
        }
        beta = next / rz;
        rz = next;
    }
    // The edges the tool can press: both ends outside the pushing shape (else the point contact
    // has it) and within the reach band of it (ToolShape::reach_band_mm, for an edge as long as
    // the longest at rest plus both ends' give), so within that band of its box too. Each point
    // says whether it can be such an end (m_rim).
    double u_max = 0.0;
    for (std::size_t i = 0; i < n; ++i) u_max = std::max(u_max, std::abs(m_u[i]));
    const double band_mm = tool.shape->reach_band_mm(contact.margin_mm, p.longest_free_edge_mm + 2.0 * u_max);
    const Eigen::AlignedBox3d edge_reach(reach.min() - Eigen::Vector3d::Constant(band_mm), reach.max() + Eigen::Vector3d::Constant(band_mm));
    // The tool's contact with the displaced points, and the load and its give for the handoff
    // (the next patch, the pose the simulation is given). A point that moved less than
    // k_linear_mm in this tick takes its linearised depth, D - u (measuring it again would change
    // nothing felt); one that moved more, or was out of the tool's reach where it was measured
    // (the layer springing back under a tool that left), is measured where it is. The edges' pass
    // reads the distances so found.
    ContactTotals out;
    double load = 0.0, moment = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
        const Eigen::Vector3d x = p.positions_mm[i] - m_u[i] * p.normals[i];
        m_displaced.positions_mm[i] = x;
        double depth = -INFINITY;
        if (m_distance[i] > -INFINITY && std::abs(m_u[i] - m_measured_u[i]) <= k_linear_mm) depth = m_distance[i] - m_u[i];
        else if (reach.contains(x)) depth = contact.margin_mm - distance(x);
        m_signed[i] = depth > -INFINITY ? contact.margin_mm - depth : INFINITY;
        m_rim[i] = depth > -INFINITY ? depth <= 0.0 && -depth < band_mm : edge_reach.contains(x);
        if (!(depth > 0.0)) continue;
        const double k = k_per_area * p.areas_mm2[i];
        const Eigen::Vector3d f = k * depth * p.normals[i]; // on the tool, out of the surface
        out.force_on_tool_n += f;
        out.torque_on_tool_n_mm += (x - tool.position).cross(f);
        out.stiffness_n_per_mm += k * p.normals[i] * p.normals[i].transpose();
        out.area_mm2 += p.areas_mm2[i];
        out.inner_reaches_surface = out.inner_reaches_surface || depth > contact.margin_mm;
        load += k * depth;
        moment += k * depth * m_u[i];
    }
    m_had_patch = true;
    m_load_n = load;
    m_give_mm = load > 0.0 ? moment / load : 0.0;
    // The edges' pass over those alone: the contact's outline, a few of the patch's hundreds of
    // edges (the capacity is reserved). Each is written whether kept or not, so that no branch is
    // mispredicted.
    m_displaced.edges.resize(p.free_edges.size());
    std::size_t kept = 0;
    for (const Eigen::Vector2i& e : p.free_edges) {
        m_displaced.edges[kept] = e;
        kept += m_rim[static_cast<std::size_t>(e[0])] & m_rim[static_cast<std::size_t>(e[1])];
    }
    m_displaced.edges.resize(kept);
    add_edge_totals(tool, contact, m_displaced, std::span<double>(m_signed.data(), n), out);
    // The stiffness is the contact's own, not the contact's in series with the layer: the layer
    // is that soft only once settled, so a proxy's step taken on it overshoots, and on a stiff
    // contact with a soft layer rings (tests/haptics/contact_patch_test.cpp).
    return out;
}

} // namespace vox::contact



