#pragma once
// The inner loop of every matrix-free product and element pass: an element's eight corner
// vectors gathered from the nodes, turned into the element's frame, multiplied by its 24 x 24
// stiffness, turned back and added into the nodes.
//
// The element's vectors are held component-major (the x of corners 0..7, then their y, then
// their z), four corners to a vector register, and so are the stiffness matrices (HexModel
// stores them in that order). Then turning eight corners by a 3 x 3 rotation is 18 whole-register
// multiply-adds instead of eight small 3 x 3 products, and the stiffness product is six
// independent sums of 24 multiply-adds, not chains that wait on each other's latency
// (fem/lanes.hpp).

#include "core/eigen_types.hpp"
#include "fem/lanes.hpp"

#include <array>
#include <cstdint>

namespace vox::fem {

/// Eight corners' 3-vectors, component-major: `v[2 * axis + c / 4][c % 4]` is corner c's `axis`.
struct CornerVectors {
    Lanes v[6];

    [[nodiscard]] double at(int corner, int axis) const { return v[2 * axis + corner / 4][corner % 4]; }
};

/// Index of corner `c`'s `axis` in the component-major order.
[[nodiscard]] constexpr int component_major(int corner, int axis) { return 8 * axis + corner; }

/// `k` (rows and columns corner-major: 3 c + axis) reordered component-major (8 axis + c).
[[nodiscard]] inline Matrix24d to_component_major(const Matrix24d& k)
{
    Matrix24d out;
    for (int c = 0; c < 8; ++c)
        for (int a = 0; a < 3; ++a)
            for (int d = 0; d < 8; ++d)
                for (int b = 0; b < 3; ++b) out(component_major(c, a), component_major(d, b)) = k(3 * c + a, 3 * d + b);
    return out;
}

/// The 3 x 3 block coupling corners c and d of a component-major stiffness.
[[nodiscard]] inline Eigen::Matrix3d corner_block(const Matrix24d& k, int c, int d)
{
    Eigen::Matrix3d out;
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) out(a, b) = k(component_major(c, a), component_major(d, b));
    return out;
}

/// The corners' vectors of a node-major array (node n's at `x[3 n]`).
[[nodiscard]] inline CornerVectors gather(const double* x, const std::array<std::uint32_t, 8>& node)
{
    CornerVectors out;
    for (int a = 0; a < 3; ++a)
        for (int h = 0; h < 2; ++h) {
            const std::uint32_t* n = &node[static_cast<std::size_t>(4 * h)];
            out.v[2 * a + h] = Lanes{x[3 * std::size_t{n[0]} + a], x[3 * std::size_t{n[1]} + a], x[3 * std::size_t{n[2]} + a],
                                     x[3 * std::size_t{n[3]} + a]};
        }
    return out;
}

/// The corner-major 24-vector `u` (3 c + axis) as corner vectors.
[[nodiscard]] inline CornerVectors from_corner_major(const Vector24d& u)
{
    return gather(u.data(), {0, 1, 2, 3, 4, 5, 6, 7});
}

[[nodiscard]] inline Vector24d to_corner_major(const CornerVectors& w)
{
    Vector24d out;
    for (int c = 0; c < 8; ++c)
        for (int a = 0; a < 3; ++a) out[3 * c + a] = w.at(c, a);
    return out;
}

/// Adds the corners' vectors into a node-major array.
inline void scatter_add(const CornerVectors& w, double* x, const std::array<std::uint32_t, 8>& node)
{
    for (int c = 0; c < 8; ++c)
        for (int a = 0; a < 3; ++a) x[3 * std::size_t{node[static_cast<std::size_t>(c)]} + static_cast<std::size_t>(a)] += w.at(c, a);
}

/// r w per corner (`transpose`: r^T w).
[[nodiscard]] inline CornerVectors turn(const Eigen::Matrix3d& r, const CornerVectors& w, bool transpose)
{
    CornerVectors out;
    for (int i = 0; i < 3; ++i)
        for (int h = 0; h < 2; ++h) {
            const double r0 = transpose ? r(0, i) : r(i, 0), r1 = transpose ? r(1, i) : r(i, 1), r2 = transpose ? r(2, i) : r(i, 2);
            out.v[2 * i + h] = r0 * w.v[h] + r1 * w.v[2 + h] + r2 * w.v[4 + h];
        }
    return out;
}

[[nodiscard]] inline CornerVectors operator-(const CornerVectors& a, const CornerVectors& b)
{
    CornerVectors out;
    for (int i = 0; i < 6; ++i) out.v[i] = a.v[i] - b.v[i];
    return out;
}

[[nodiscard]] inline CornerVectors operator*(double s, const CornerVectors& a)
{
    CornerVectors out;
    for (int i = 0; i < 6; ++i) out.v[i] = s * a.v[i];
    return out;
}

/// Every corner's vector less a shared one (displacements relative to corner 0, say).
[[nodiscard]] inline CornerVectors minus(const CornerVectors& a, const Eigen::Vector3d& b)
{
    CornerVectors out;
    for (int i = 0; i < 6; ++i) out.v[i] = a.v[i] - b[i / 2];
    return out;
}

[[nodiscard]] inline double dot(const CornerVectors& a, const CornerVectors& b)
{
    Lanes sum = a.v[0] * b.v[0];
    for (int i = 1; i < 6; ++i) sum += a.v[i] * b.v[i];
    return (sum[0] + sum[1]) + (sum[2] + sum[3]);
}

/// sum over corners of w_c g_c^T, for g the corners' rows of `gradient` (the deformation
/// gradient of displacements w, say).
[[nodiscard]] inline Eigen::Matrix3d outer_sum(const CornerVectors& w, const Eigen::Matrix<double, 8, 3>& gradient)
{
    Eigen::Matrix3d out;
    for (int j = 0; j < 3; ++j) {
        Lanes g[2];
        __builtin_memcpy(g, gradient.col(j).data(), sizeof g);
        for (int i = 0; i < 3; ++i) {
            const Lanes sum = w.v[2 * i] * g[0] + w.v[2 * i + 1] * g[1];
            out(i, j) = (sum[0] + sum[1]) + (sum[2] + sum[3]);
        }
    }
    return out;
}

/// m g_c for every corner c, g_c the corner's row of `gradient` (the derivative of a function of
/// the deformation gradient F with respect to the corners, m the derivative with respect to F).
[[nodiscard]] inline CornerVectors gradient_times(const Eigen::Matrix3d& m, const Eigen::Matrix<double, 8, 3>& gradient)
{
    CornerVectors out;
    for (int i = 0; i < 3; ++i)
        for (int h = 0; h < 2; ++h)
            for (int k = 0; k < 4; ++k) {
                const int c = 4 * h + k;
                out.v[2 * i + h][k] = m(i, 0) * gradient(c, 0) + m(i, 1) * gradient(c, 1) + m(i, 2) * gradient(c, 2);
            }
    return out;
}

/// k u for a component-major stiffness: column j of k times u's entry j, summed into six
/// independent registers.
[[nodiscard]] inline CornerVectors stiffness_times(const Matrix24d& k, const CornerVectors& u)
{
    const double* column = k.data();
    auto load = [](const double* at) {
        Lanes x;
        __builtin_memcpy(&x, at, sizeof x);
        return x;
    };
    CornerVectors y;
    for (int i = 0; i < 6; ++i) y.v[i] = Lanes{};
#pragma GCC unroll 24
    for (int j = 0; j < 24; ++j, column += 24) {
        const double uj = u.v[j / 4][j % 4];
        for (int i = 0; i < 6; ++i) y.v[i] += load(column + 4 * i) * uj;
    }
    return y;
}

} // namespace vox::fem
