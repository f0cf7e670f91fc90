#include "io/winding_number.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace vox::io {
namespace {

constexpr int k_leaf_size = 8;
constexpr double k_four_pi = 4.0 * std::numbers::pi;

} // namespace

double triangle_solid_angle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                            const Eigen::Vector3d& q)
{
    const Eigen::Vector3d qa = a - q;
    const Eigen::Vector3d qb = b - q;
    const Eigen::Vector3d qc = c - q;
    const double la = qa.norm();
    const double lb = qb.norm();
    const double lc = qc.norm();
    const double numerator = qa.dot(qb.cross(qc));
    const double denominator = la * lb * lc + qa.dot(qb) * lc + qb.dot(qc) * la + qc.dot(qa) * lb;
    // atan2 keeps the quadrant, so angles beyond pi/2 (q close to the triangle) come out right.
    return 2.0 * std::atan2(numerator, denominator);
}

double winding_number_exact(const TriangleMesh& mesh, const Eigen::Vector3d& q)
{
    double sum = 0.0;
    for (const Eigen::Vector3i& t : mesh.triangles)
        sum += triangle_solid_angle(mesh.vertices[static_cast<std::size_t>(t[0])],
                                    mesh.vertices[static_cast<std::size_t>(t[1])],
                                    mesh.vertices[static_cast<std::size_t>(t[2])], q);
    return sum / k_four_pi;
}

WindingNumber::WindingNumber(const TriangleMesh& mesh, double beta) : m_beta(beta)
{
    m_triangles.reserve(mesh.triangles.size());
    for (const Eigen::Vector3i& t : mesh.triangles)
        m_triangles.push_back({mesh.vertices[static_cast<std::size_t>(t[0])],
                               mesh.vertices[static_cast<std::size_t>(t[1])],
                               mesh.vertices[static_cast<std::size_t>(t[2])]});
    if (!m_triangles.empty()) build(0, static_cast<int>(m_triangles.size()));
}

int WindingNumber::build(int first, int count)
{
    const std::size_t index = m_nodes.size();
    Node node;
    node.first = first;
    node.count = count;
    fit_expansion(node);
    m_nodes.push_back(node);
    if (count <= k_leaf_size) return static_cast<int>(index);

    // Median split of the centroids along the box's longest axis: a balanced tree of depth log2(n).
    int axis = 0;
    node.box.sizes().maxCoeff(&axis);
    const auto begin = m_triangles.begin() + first;
    const int half = count / 2;
    std::nth_element(begin, begin + half, begin + count, [axis](const Triangle& s, const Triangle& t) {
        return s.a[axis] + s.b[axis] + s.c[axis] < t.a[axis] + t.b[axis] + t.c[axis];
    });
    build(first, half);
    m_nodes[index].second_child = build(first + half, count - half);
    return static_cast<int>(index);
}

void WindingNumber::fit_expansion(Node& node) const
{
    double area = 0.0;
    Eigen::Vector3d weighted = Eigen::Vector3d::Zero();
    for (int i = node.first; i < node.first + node.count; ++i) {
        const Triangle& t = m_triangles[static_cast<std::size_t>(i)];
        node.box.extend(t.a);
        node.box.extend(t.b);
        node.box.extend(t.c);
        const double a = 0.5 * (t.b - t.a).cross(t.c - t.a).norm();
        area += a;
        weighted += a * (t.a + t.b + t.c) / 3.0;
    }
    node.centre = area > 0.0 ? Eigen::Vector3d(weighted / area) : node.box.center();
    for (int i = node.first; i < node.first + node.count; ++i) {
        const Triangle& t = m_triangles[static_cast<std::size_t>(i)];
        const Eigen::Vector3d a = t.a - node.centre;
        const Eigen::Vector3d b = t.b - node.centre;
        const Eigen::Vector3d c = t.c - node.centre;
        const Eigen::Vector3d area_normal = 0.5 * (b - a).cross(c - a); // area * unit normal
        const Eigen::Vector3d sum = a + b + c;
        node.dipole += area_normal;
        node.first_moment += (sum / 3.0) * area_normal.transpose(); // exact: a linear integrand
        // Integral over the triangle of d d^T, d = point - p~, is (area / 12) (sum v v^T + s s^T) for
        // corners v and s = sum v; the area comes in with area_normal.
        const Eigen::Matrix3d second =
            (a * a.transpose() + b * b.transpose() + c * c.transpose() + sum * sum.transpose()) / 12.0;
        for (int k = 0; k < 3; ++k) node.second_moment[static_cast<std::size_t>(k)] += area_normal[k] * second;
        node.radius = std::max({node.radius, a.norm(), b.norm(), c.norm()});
    }
    for (int k = 0; k < 3; ++k) {
        const Eigen::Matrix3d& m = node.second_moment[static_cast<std::size_t>(k)];
        node.second_moment_column_sum += m.col(k);
        node.second_moment_trace[k] = m.trace();
    }
}

double WindingNumber::far_field(const Node& node, const Eigen::Vector3d& q) const
{
    // Solid angle = integral over the cluster of n . g(r + d) dA, with g(x) = x / |x|^3, r = p~ - q
    // and d = point - p~. Taylor expansion in d to second order, as in Barill et al. 2018:
    //   g(r) . sum(a n)                                      dipole
    // + dg(r) : sum(a (c - p~) n^T)                          first moment, dg = I/r^3 - 3 r r^T/r^5
    // + 1/2 d2g(r) . sum(n_k integral d d^T dA)             second moment, contracted below.
    const Eigen::Vector3d r = node.centre - q;
    const double r2 = r.squaredNorm();
    const double inv_r = 1.0 / std::sqrt(r2);
    const double inv_r3 = inv_r / r2;
    const double inv_r5 = inv_r3 / r2;
    const double inv_r7 = inv_r5 / r2;
    const double dipole = inv_r3 * r.dot(node.dipole);
    const double first = inv_r3 * node.first_moment.trace() - 3.0 * inv_r5 * r.dot(node.first_moment * r);
    // d2g_k/dx_j dx_l = -3 (delta_jk x_l + delta_jl x_k + delta_kl x_j) / r^5 + 15 x_j x_k x_l / r^7.
    double cubic = 0.0;
    for (int k = 0; k < 3; ++k) cubic += r[k] * r.dot(node.second_moment[static_cast<std::size_t>(k)] * r);
    const double linear = 2.0 * r.dot(node.second_moment_column_sum) + r.dot(node.second_moment_trace);
    const double second = 0.5 * (15.0 * inv_r7 * cubic - 3.0 * inv_r5 * linear);
    return dipole + first + second;
}

double WindingNumber::leaf_exact(const Node& node, const Eigen::Vector3d& q) const
{
    double sum = 0.0;
    for (int i = node.first; i < node.first + node.count; ++i) {
        const Triangle& t = m_triangles[static_cast<std::size_t>(i)];
        sum += triangle_solid_angle(t.a, t.b, t.c, q);
    }
    return sum;
}

double WindingNumber::at(const Eigen::Vector3d& q) const
{
    if (m_nodes.empty()) return 0.0;
    // Median splits give depth <= log2(#triangles) + 1, so the stack never holds more than 64.
    std::array<int, 64> stack{};
    int top = 0;
    stack[static_cast<std::size_t>(top++)] = 0;
    double solid_angle = 0.0;
    while (top > 0) {
        const int index = stack[static_cast<std::size_t>(--top)];
        const Node& node = m_nodes[static_cast<std::size_t>(index)];
        if ((q - node.centre).squaredNorm() > m_beta * m_beta * node.radius * node.radius) {
            solid_angle += far_field(node, q);
        } else if (node.second_child < 0) {
            solid_angle += leaf_exact(node, q);
        } else {
            stack[static_cast<std::size_t>(top++)] = index + 1;
            stack[static_cast<std::size_t>(top++)] = node.second_child;
        }
    }
    return solid_angle / k_four_pi;
}

} // namespace vox::io
