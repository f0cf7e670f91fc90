#include "grid/hex8.hpp"

#include <cmath>

namespace vox::grid {
namespace {
/// 1-D factor of a shape function: t for the corner's +side, 1 - t for its -side.
double factor(int bit, double t) { return bit ? t : 1.0 - t; }
double factor_slope(int bit) { return bit ? 1.0 : -1.0; }

/// Gradient of N_c with respect to physical coordinates at local t, box edges `size`.
Eigen::Vector3d gradient(int c, const Eigen::Vector3d& t, const Eigen::Vector3d& size)
{
    const int bx = c & 1, by = (c >> 1) & 1, bz = (c >> 2) & 1;
    return {factor_slope(bx) * factor(by, t.y()) * factor(bz, t.z()) / size.x(),
            factor(bx, t.x()) * factor_slope(by) * factor(bz, t.z()) / size.y(),
            factor(bx, t.x()) * factor(by, t.y()) * factor_slope(bz) / size.z()};
}

template <class F> void for_each_gauss_point(F&& f)
{
    const double g = 0.5 / std::sqrt(3.0);
    const double pts[2] = {0.5 - g, 0.5 + g};
    for (double z : pts)
        for (double y : pts)
            for (double x : pts) f(Eigen::Vector3d(x, y, z), 0.125);
}
} // namespace

Lame lame_from_young_poisson(double e, double nu)
{
    return {e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), e / (2.0 * (1.0 + nu))};
}

double hex8_shape(int c, const Eigen::Vector3d& t)
{
    return factor(c & 1, t.x()) * factor((c >> 1) & 1, t.y()) * factor((c >> 2) & 1, t.z());
}

Matrix24d hex8_stiffness(const Eigen::Vector3d& size, const Lame& m)
{
    Matrix24d k = Matrix24d::Zero();
    const double volume = size.prod();
    for_each_gauss_point([&](const Eigen::Vector3d& t, double w) {
        Eigen::Matrix<double, 3, 8> g;
        for (int c = 0; c < 8; ++c) g.col(c) = gradient(c, t, size);
        const double wv = w * volume;
        for (int c = 0; c < 8; ++c)
            for (int d = 0; d < 8; ++d) {
                // K_(ci)(dj) = lambda g_ci g_dj + mu (g_cj g_di + delta_ij g_c . g_d)
                const double dot = g.col(c).dot(g.col(d));
                for (int i = 0; i < 3; ++i)
                    for (int j = 0; j < 3; ++j)
                        k(3 * c + i, 3 * d + j) +=
                            wv * (m.lambda * g(i, c) * g(j, d) + m.mu * (g(j, c) * g(i, d) + (i == j ? dot : 0.0)));
            }
    });
    return k;
}

Matrix8d hex8_mass(const Eigen::Vector3d& size, double rho)
{
    Matrix8d m = Matrix8d::Zero();
    const double mass = rho * size.prod();
    for_each_gauss_point([&](const Eigen::Vector3d& t, double w) {
        Eigen::Matrix<double, 8, 1> n;
        for (int c = 0; c < 8; ++c) n[c] = hex8_shape(c, t);
        m += w * mass * n * n.transpose();
    });
    return m;
}

Matrix24d expand_to_dofs(const Matrix8d& s)
{
    Matrix24d out = Matrix24d::Zero();
    for (int c = 0; c < 8; ++c)
        for (int d = 0; d < 8; ++d)
            for (int i = 0; i < 3; ++i) out(3 * c + i, 3 * d + i) = s(c, d);
    return out;
}

} // namespace vox::grid
