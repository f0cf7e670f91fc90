#pragma once
// How a model's elements are shaped after a step: the inverted ones and the most stretched one,
// from each element's deformation gradient F. The same measure for every method's elements
// (hexahedra at their material centroid, tetrahedra), so that stats.json and the frame loop's
// divergence check read them alike.

#include <Eigen/Core>
#include <Eigen/LU> // determinant()

#include <cmath>
#include <cstddef>

namespace vox::fem {

/// How the elements of a model are shaped after a step, from each one's deformation gradient F
/// (hexahedra: at the material centroid).
struct ElementShapes {
    std::size_t inverted = 0;  ///< det F zero or less, or not finite
    /// The largest |F|_F / sqrt(3): the root mean square of an element's stretches, 1 at rest and
    /// under any rotation; infinite for an F that is not finite. What tells a run that is
    /// running away from one that is only deformed.
    double max_stretch = 1.0;
    Eigen::Vector3d most_stretched_m = Eigen::Vector3d::Zero(); ///< that element's corners' mean now, world m
    /// Adds one element's F, its corners' mean `where` (world m).
    void add(const Eigen::Matrix3d& f, double orientation, const Eigen::Vector3d& where)
    {
        inverted += !(orientation * f.determinant() > 0.0);
        const double stretch = f.allFinite() ? f.norm() / std::sqrt(3.0) : INFINITY;
        if (stretch > max_stretch) {
            max_stretch = stretch;
            most_stretched_m = where;
        }
    }
};

} // namespace vox::fem
