#pragma once
// What keeps a squeezed element from losing its volume or turning inside out.
//
// Linear (corotational) elasticity measures a volume change by the trace of the strain,
// tr(S) - 3 with S = R^T F, which stays near zero when an element is flattened to a tenth of its
// height and bulges sideways (S = diag(0.1, 1.45, 1.45): J = det F = 0.21): a soft block pinched by
// a probe lost 6 % of its volume at no cost. Where an element has lost more than a few percent of
// its volume, the correction replaces the linear model's volumetric energy at its centroid,
// lambda V (tr S - 3)^2 / 2, by one of the volume ratio J itself, lambda V phi(J), as a
// hyperelastic (neo-Hookean) solid has it:
//
//   psi = lambda V s(J) (phi(J) - (tr S - 3)^2 / 2),   phi(J) = J - 1 - log J,
//
// phi grows without bound as the element is flattened. s blends it in (a quintic smoothstep, C2)
// from J = k_volume_blend_start (0.98: the linear model untouched) to k_volume_blend_full (0.9):
// the linear model, and every analytic test of it, stays exact in tension and moderate
// compression, where it is accurate. Inversion-safe in the manner of Irving, Teran and Fedkiw
// 2004 ("Invertible finite elements for robust simulation of large deformation"): below J =
// k_volume_clamp phi goes on as its quadratic expansion there, so an element flattened or pushed
// through itself has a finite energy and a force that turns it back out, never a log of a
// negative number. A plastic element's own volume change (its plastic strain eps_p) is its
// rest: J is taken relative to det(I + eps_p), tr S - 3 less tr eps_p.
//
// Its gradient in F is a combination of cof F (= dJ/dF) and R (= d tr S / dF: R maximises
// tr(R^T F)). Its Hessian is indefinite; the system takes the positive part of its restriction to
// the plane of cof F and R (Teran et al. 2005 project element Hessians the same way), the
// curvature of cof F and R themselves left out.

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <cmath>

namespace vox::fem {

/// Below this volume ratio phi is extended quadratically (inversion-safe).
inline constexpr double k_volume_clamp = 0.1;
/// The correction starts below this volume ratio and is whole below the next.
inline constexpr double k_volume_blend_start = 0.98;
inline constexpr double k_volume_blend_full = 0.9;

/// A function of J and its first two derivatives.
struct VolumeTerm {
    double value = 0.0;
    double slope = 0.0;
    double curvature = 0.0;
};

/// phi(J) = J - 1 - log J, quadratic below k_volume_clamp (and for a J that is not finite).
[[nodiscard]] inline VolumeTerm volume_term(double j)
{
    const double c = std::max(j, k_volume_clamp); // also for a NaN j: the clamp
    const double e = c - 1.0 - std::log(c), slope = 1.0 - 1.0 / c, curvature = 1.0 / (c * c);
    const double d = std::isfinite(j) ? j - c : 0.0; // 0 above the clamp
    return {e + slope * d + 0.5 * curvature * d * d, slope + curvature * d, curvature};
}

/// s(J): 0 from k_volume_blend_start up, 1 from k_volume_blend_full down, a quintic smoothstep
/// between.
[[nodiscard]] inline VolumeTerm volume_blend(double j)
{
    const double width = k_volume_blend_start - k_volume_blend_full;
    const double x = std::clamp((k_volume_blend_start - j) / width, 0.0, 1.0);
    if (!std::isfinite(j)) return {1.0, 0.0, 0.0};
    return {x * x * x * (10.0 - 15.0 * x + 6.0 * x * x), -30.0 * x * x * (1.0 - x) * (1.0 - x) / width,
            60.0 * x * (1.0 - x) * (1.0 - 2.0 * x) / (width * width)};
}

/// The positive part of the correction's Hessian: dF -> sum_ij q(i, j) (basis_j : dF) basis_i,
/// the basis orthonormal in the Frobenius product; 0 (inactive) where the correction is.
struct VolumeHessian {
    std::array<Eigen::Matrix3d, 2> basis{Eigen::Matrix3d::Zero(), Eigen::Matrix3d::Zero()};
    Eigen::Matrix2d q = Eigen::Matrix2d::Zero();

    [[nodiscard]] bool active() const { return q.trace() > 0.0; }
    /// The same in a frame turned by `frame` (world = frame * local).
    [[nodiscard]] VolumeHessian turned(const Eigen::Matrix3d& frame) const { return {{frame * basis[0], frame * basis[1]}, q}; }
    /// Its product with dF.
    [[nodiscard]] Eigen::Matrix3d times(const Eigen::Matrix3d& df) const
    {
        const Eigen::Vector2d s = q * Eigen::Vector2d(basis[0].cwiseProduct(df).sum(), basis[1].cwiseProduct(df).sum());
        return s[0] * basis[0] + s[1] * basis[1];
    }
    /// The 3 x 3 block between two corners whose shape-function gradients are `ga` and `gb`:
    /// sum_ij q(i, j) (basis_i ga)(basis_j gb)^T.
    [[nodiscard]] Eigen::Matrix3d block(const Eigen::Vector3d& ga, const Eigen::Vector3d& gb) const
    {
        Eigen::Matrix<double, 3, 2> a, b;
        a << basis[0] * ga, basis[1] * ga;
        b << basis[0] * gb, basis[1] * gb;
        return a * q * b.transpose();
    }
};

/// The correction of one element: its energy, gradient and the positive part of its Hessian, all
/// in the frame of the deformation gradient it was given.
struct VolumeCorrection {
    double energy = 0.0;
    Eigen::Matrix3d gradient = Eigen::Matrix3d::Zero(); ///< d psi / d F
    VolumeHessian hessian;
};

/// At deformation gradient `f`, corotational rotation `r` (maximising tr(r^T f)), for
/// lambda V = `lambda_v` (J); a plastic element's plastic volume ratio and strain trace.
[[nodiscard]] inline VolumeCorrection volume_correction(const Eigen::Matrix3d& f, const Eigen::Matrix3d& r, double lambda_v,
                                                        double plastic_volume = 1.0, double plastic_trace = 0.0)
{
    VolumeCorrection out;
    Eigen::Matrix3d dj; // d J_e / d F = cof F / det(I + eps_p)
    dj.col(0) = f.col(1).cross(f.col(2));
    dj.col(1) = f.col(2).cross(f.col(0));
    dj.col(2) = f.col(0).cross(f.col(1));
    const double j = f.col(0).dot(dj.col(0)) / plastic_volume;
    const VolumeTerm s = volume_blend(j);
    if (s.value == 0.0 && s.slope == 0.0) return out;
    dj /= plastic_volume;
    const double t = (r.transpose() * f).trace() - 3.0 - plastic_trace;
    const VolumeTerm phi = volume_term(j);
    const double c = phi.value - 0.5 * t * t;
    out.energy = lambda_v * s.value * c;
    out.gradient = lambda_v * ((s.slope * c + s.value * phi.slope) * dj - s.value * t * r);
    // In the (dj, r) coordinates the Hessian's part in their plane is
    // [[s'' c + 2 s' phi' + s phi'', -s' t], [-s' t, -s]]; turned into an orthonormal basis
    // (dj = b e0, r = c0 e0 + c1 e1), its negative eigenvalues dropped.
    const double b = dj.norm();
    if (!(b > 1e-12) || !std::isfinite(b)) return out;
    out.hessian.basis[0] = dj / b;
    const double c0 = r.cwiseProduct(out.hessian.basis[0]).sum();
    const Eigen::Matrix3d rest = r - c0 * out.hessian.basis[0];
    const double c1 = rest.norm();
    if (c1 > 1e-9) out.hessian.basis[1] = rest / c1;
    Eigen::Matrix2d h, to;
    h << s.curvature * c + 2.0 * s.slope * phi.slope + s.value * phi.curvature, -s.slope * t, -s.slope * t, -s.value;
    to << b, c0, 0.0, c1;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(to * h * to.transpose());
    const Eigen::Vector2d kept = eigen.eigenvalues().cwiseMax(0.0);
    out.hessian.q = lambda_v * eigen.eigenvectors() * kept.asDiagonal() * eigen.eigenvectors().transpose();
    return out;
}

} // namespace vox::fem
