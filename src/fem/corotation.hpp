#pragma once
// The rotation of a corotational element: the rotation R that maximises tr(R^T A), found by the
// iteration of Müller, Bender, Chentanez and Macklin 2016 ("A Robust Method to Extract the
// Rotational Part of Deformations") with Newton steps, warm-started from the previous step's
// rotation. For det A > 0
// it is the orthogonal factor of the polar decomposition; unlike the SVD factor it stays a proper
// rotation when an element is inverted (det A <= 0), so the elastic force pushes the element back
// out instead of treating the inverted state as a mirrored rest state. Warm-started it needs two
// or three iterations a step, several times cheaper than a 3 x 3 SVD.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "fem/lanes.hpp"

#include <cmath>

namespace vox::fem {

/// Updates `q[l]` to the rotation nearest `a[l]` for `count` (1 to 4) elements at once, one in
/// each vector lane; keeps `q[l]` when `a[l]` is not finite.
///
/// Each iteration turns R by the world-frame rotation vector omega that maximises tr(R^T A) to
/// second order: the gradient is the torque sum_i r_i x a_i and the Hessian is tr(B) I - sym(B),
/// B = A R^T, so omega = (tr(B) I - sym(B))^-1 torque, a Newton step that converges
/// quadratically. Müller et al. replace the Hessian by tr(B) I, which converges only linearly
/// (about a third of the error a step near a rigid state: 20 iterations to 1e-12 from a step's
/// worth of turning); their step is kept where the Hessian is not positive definite (far from
/// the answer, an inverted element), since it always goes uphill. The Newton system is solved by
/// its LDL^T factors, taken where every pivot is safely positive (over 1e-8 |tr B|, far from
/// round-off). The turn is applied as the quaternion (1, omega / 2) normalised, a rotation by
/// 2 atan(|omega| / 2): off by |omega|^3 / 12, which the next iteration takes up, and no sine or
/// cosine. A Newton step under 1e-6 rad leaves an error of its square, 1e-12 rad, so a lane stops
/// there; Müller's steps go on to 1e-12. The lanes run in step (a lane that has stopped keeps its
/// rotation) until every lane has stopped: the element pass takes four elements' rotations at the
/// cost of about one, since one element's iteration is a chain of dependent operations.
inline void extract_rotations(const Eigen::Matrix3d* const a[], Eigen::Quaterniond* const q[], int count, int max_iterations = 30)
{
    // Lanes without an element hold the identity, which is its own rotation.
    const Lanes one{1, 1, 1, 1};
    Lanes m[3][3] = {{one, Lanes{}, Lanes{}}, {Lanes{}, one, Lanes{}}, {Lanes{}, Lanes{}, one}}, w = one, x{}, y{}, z{};
    Mask running{};
    for (int l = 0; l < count; ++l) {
        if (!a[l]->allFinite()) continue;
        running[l] = -1;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) m[i][j][l] = (*a[l])(i, j);
        w[l] = q[l]->w(), x[l] = q[l]->x(), y[l] = q[l]->y(), z[l] = q[l]->z();
    }
    for (int it = 0; it < max_iterations && any(running); ++it) {
        const Lanes tx = 2.0 * x, ty = 2.0 * y, tz = 2.0 * z;
        const Lanes r[3][3] = {{1.0 - (ty * y + tz * z), tx * y - tz * w, tx * z + ty * w},
                               {tx * y + tz * w, 1.0 - (tx * x + tz * z), ty * z - tx * w},
                               {tx * z - ty * w, ty * z + tx * w, 1.0 - (tx * x + ty * y)}};
        Lanes torque[3] = {Lanes{}, Lanes{}, Lanes{}}, b[3][3];
        for (int k = 0; k < 3; ++k) {
            torque[0] += r[1][k] * m[2][k] - r[2][k] * m[1][k];
            torque[1] += r[2][k] * m[0][k] - r[0][k] * m[2][k];
            torque[2] += r[0][k] * m[1][k] - r[1][k] * m[0][k];
        }
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) b[i][j] = m[i][0] * r[j][0] + m[i][1] * r[j][1] + m[i][2] * r[j][2];
        const Lanes alignment = b[0][0] + b[1][1] + b[2][2];
        const Lanes h00 = alignment - b[0][0], h11 = alignment - b[1][1], h22 = alignment - b[2][2];
        const Lanes h01 = -0.5 * (b[0][1] + b[1][0]), h02 = -0.5 * (b[0][2] + b[2][0]), h12 = -0.5 * (b[1][2] + b[2][1]);
        const Lanes l10 = h01 / h00, l20 = h02 / h00, d1 = h11 - l10 * h01;
        const Lanes l21 = (h12 - l20 * h01) / d1, d2 = h22 - l20 * h02 - l21 * l21 * d1;
        const Lanes pivot = 1e-8 * (lane_abs(alignment) + 1e-300);
        const Mask newton = (h00 > pivot) & (d1 > pivot) & (d2 > pivot); // false for NaN too
        const Lanes z1 = torque[1] - l10 * torque[0], z2 = torque[2] - l20 * torque[0] - l21 * z1;
        const Lanes o2 = z2 / d2, o1 = z1 / d1 - l21 * o2, o0 = torque[0] / h00 - l10 * o1 - l20 * o2;
        const Lanes muller = 1.0 / (lane_abs(alignment) + 1e-9);
        const Lanes ox = newton ? o0 : torque[0] * muller, oy = newton ? o1 : torque[1] * muller, oz = newton ? o2 : torque[2] * muller;
        const Lanes angle2 = ox * ox + oy * oy + oz * oz;
        const Mask turning = running & (angle2 >= 1e-24); // a step under 1e-12 rad, or NaN: done
        // (1, omega / 2) * q, normalised.
        const Lanes hx = 0.5 * ox, hy = 0.5 * oy, hz = 0.5 * oz;
        const Lanes nw = w - (hx * x + hy * y + hz * z);
        const Lanes nx = x + hx * w + (hy * z - hz * y), ny = y + hy * w + (hz * x - hx * z), nz = z + hz * w + (hx * y - hy * x);
        const Lanes scale = 1.0 / lane_sqrt(nw * nw + nx * nx + ny * ny + nz * nz);
        w = turning ? nw * scale : w, x = turning ? nx * scale : x, y = turning ? ny * scale : y, z = turning ? nz * scale : z;
        running = turning & ~(newton & (angle2 < 1e-12)); // quadratic: the error left is about angle^2
    }
    for (int l = 0; l < count; ++l)
        if (a[l]->allFinite()) *q[l] = Eigen::Quaterniond(w[l], x[l], y[l], z[l]);
}

/// The same for one element.
inline void extract_rotation(const Eigen::Matrix3d& a, Eigen::Quaterniond& q, int max_iterations = 30)
{
    const Eigen::Matrix3d* const from[] = {&a};
    Eigen::Quaterniond* const to[] = {&q};
    extract_rotations(from, to, 1, max_iterations);
}

/// Adds rotation q to a running sum of quaternions with the sign nearer the sum (q and -q are the
/// same rotation); the normalised sum is the mean rotation.
inline void accumulate_rotation(Eigen::Vector4d& sum, const Eigen::Quaterniond& q)
{
    const Eigen::Vector4d c = q.coeffs();
    sum += sum.dot(c) < 0.0 ? -c : c;
}

} // namespace vox::fem
