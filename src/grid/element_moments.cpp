#include "grid/element_moments.hpp"

#include <algorithm>

namespace vox::grid {
namespace {

/// 6 * integral over [i, i+1] of u^a, a = 0, 1, 2: 6, 6i + 3, 6i^2 + 6i + 2.
std::array<std::int64_t, 3> voxel_axis(std::int64_t i) { return {6, 6 * i + 3, 6 * i * i + 6 * i + 2}; }

/// 6 * integral over [o, o + s] of u^a, as sums of the voxel terms: sums of i and i^2 in closed form.
std::array<std::int64_t, 3> box_axis(std::int64_t o, std::int64_t s)
{
    auto sum_sq = [](std::int64_t n) { return n * (n - 1) * (2 * n - 1) / 6; }; // sum_{i < n} i^2
    const std::int64_t sum_i = s * o + s * (s - 1) / 2;
    const std::int64_t sum_i2 = sum_sq(o + s) - sum_sq(o);
    return {6 * s, 6 * sum_i + 3 * s, 6 * sum_i2 + 6 * sum_i + 2 * s};
}

void add_outer(Moments& m, const std::array<std::int64_t, 3>& x, const std::array<std::int64_t, 3>& y,
               const std::array<std::int64_t, 3>& z, int sign)
{
    for (int c = 0; c < 3; ++c)
        for (int b = 0; b < 3; ++b)
            for (int a = 0; a < 3; ++a) m[a + 3 * b + 9 * c] += sign * x[a] * y[b] * z[c];
}

/// A polynomial of degree <= 2 in one variable: p[0] + p[1] u + p[2] u^2.
using Poly = std::array<double, 3>;
Poly multiply(const std::array<double, 2>& f, const std::array<double, 2>& g)
{
    return {f[0] * g[0], f[0] * g[1] + f[1] * g[0], f[1] * g[1]};
}

/// The 1-D factor of a corner's shape function as a polynomial in u (voxel units), cell edge n:
/// u / n on the corner's + side, 1 - u / n on its - side; and its derivative in u.
std::array<double, 2> shape_factor(int bit, double n) { return bit ? std::array{0.0, 1.0 / n} : std::array{1.0, -1.0 / n}; }
std::array<double, 2> slope_factor(int bit, double n) { return {bit ? 1.0 / n : -1.0 / n, 0.0}; }

/// Coefficients over the 27 moments of the product of three per-axis polynomials, times `scale`.
std::array<double, 27> coefficients(const Poly& px, const Poly& py, const Poly& pz, double scale)
{
    std::array<double, 27> out{};
    for (int c = 0; c < 3; ++c)
        for (int b = 0; b < 3; ++b)
            for (int a = 0; a < 3; ++a) out[a + 3 * b + 9 * c] = scale * px[a] * py[b] * pz[c];
    return out;
}

double dot(const std::array<double, 27>& coeff, const Moments& m)
{
    double s = 0.0;
    for (int k = 0; k < 27; ++k)
        if (coeff[k] != 0.0) s += coeff[k] * static_cast<double>(m[k]);
    return s;
}

} // namespace

void add_voxel_moments(Moments& m, const Eigen::Vector3i& l, int sign)
{
    add_outer(m, voxel_axis(l.x()), voxel_axis(l.y()), voxel_axis(l.z()), sign);
}

void add_box_moments(Moments& m, const Eigen::Vector3i& o, int size, int sign)
{
    add_outer(m, box_axis(o.x(), size), box_axis(o.y(), size), box_axis(o.z(), size), sign);
}

void update_content(ElementContent& content, std::int32_t material, const Eigen::Vector3i& local, int sign)
{
    auto it = std::lower_bound(content.begin(), content.end(), material,
                               [](const MaterialMoments& m, std::int32_t mat) { return m.material < mat; });
    if (it == content.end() || it->material != material) it = content.insert(it, MaterialMoments{material, 0, {}});
    add_voxel_moments(it->moments, local, sign);
    it->voxels += sign;
    if (it->voxels == 0) content.erase(it);
}

MomentMatrices::MomentMatrices(int level, const Eigen::Vector3d& h)
{
    const double n = static_cast<double>(1 << level);
    // dx = hx hy hz du, d/dx_i = (1 / h_i) d/du_i, and the moments carry a factor 216.
    const double volume_scale = h.prod() / 216.0;
    for (int c = 0; c < 8; ++c)
        for (int d = 0; d < 8; ++d) {
            const int bc[3] = {c & 1, (c >> 1) & 1, (c >> 2) & 1};
            const int bd[3] = {d & 1, (d >> 1) & 1, (d >> 2) & 1};
            Poly p[3];
            for (int a = 0; a < 3; ++a) p[a] = multiply(shape_factor(bc[a], n), shape_factor(bd[a], n));
            m_shape[8 * c + d] = coefficients(p[0], p[1], p[2], volume_scale);
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) {
                    for (int a = 0; a < 3; ++a) {
                        const auto fc = a == i ? slope_factor(bc[a], n) : shape_factor(bc[a], n);
                        const auto fd = a == j ? slope_factor(bd[a], n) : shape_factor(bd[a], n);
                        p[a] = multiply(fc, fd);
                    }
                    m_gradient[8 * c + d][3 * i + j] = coefficients(p[0], p[1], p[2], volume_scale / (h[i] * h[j]));
                }
        }
}

Matrix24d MomentMatrices::stiffness(const ElementContent& content, std::span<const ElasticMaterial> materials) const
{
    Matrix24d k = Matrix24d::Zero();
    for (const MaterialMoments& mm : content) {
        const Lame& lame = materials[mm.material].lame;
        for (int c = 0; c < 8; ++c)
            for (int d = c; d < 8; ++d) {
                // G_ij = integral dN_c/dx_i dN_d/dx_j; K_(ci)(dj) = lambda G_ij + mu (G_ji + delta_ij tr G).
                Eigen::Matrix3d g;
                for (int i = 0; i < 3; ++i)
                    for (int j = 0; j < 3; ++j) g(i, j) = dot(m_gradient[8 * c + d][3 * i + j], mm.moments);
                const Eigen::Matrix3d block =
                    lame.lambda * g + lame.mu * (g.transpose() + g.trace() * Eigen::Matrix3d::Identity());
                k.block<3, 3>(3 * c, 3 * d) += block;
                if (d != c) k.block<3, 3>(3 * d, 3 * c) += block.transpose();
            }
    }
    return k;
}

Matrix8d MomentMatrices::mass(const ElementContent& content, std::span<const ElasticMaterial> materials) const
{
    Matrix8d m = Matrix8d::Zero();
    for (const MaterialMoments& mm : content)
        for (int c = 0; c < 8; ++c)
            for (int d = 0; d < 8; ++d) m(c, d) += materials[mm.material].density_kg_m3 * dot(m_shape[8 * c + d], mm.moments);
    return m;
}

} // namespace vox::grid
