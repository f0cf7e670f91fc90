#include "fem/factor_failure.hpp"

#include <cstdio>

namespace vox::fem {

std::string fallback_note(const char* name, const FactorFailure& f, const Eigen::Vector3d* where_m, bool quasi_static, bool anything_held)
{
    std::string note = std::string(name) + " preconditioner failed: the step's matrix is ";
    char buffer[96];
    if (f.not_positive_definite) {
        note += "not positive definite";
    } else if (f.pivot_ratio > 0.0) {
        std::snprintf(buffer, sizeof buffer, "nearly singular (smallest pivot %.1e of the largest)", f.pivot_ratio);
        note += buffer;
    } else {
        note += "singular";
    }
    if (where_m) {
        std::snprintf(buffer, sizeof buffer, " at the node at (%.1f, %.1f, %.1f) mm", 1e3 * where_m->x(), 1e3 * where_m->y(),
                      1e3 * where_m->z());
        note += buffer;
    }
    // Without mass only the holds keep K from being singular; with mass M/h^2 does, so there a hold
    // cannot be the cause and is not suggested.
    if (!f.not_positive_definite && quasi_static) note += anything_held ? " (a piece that nothing holds?)" : " (nothing holds the object)";
    return note + "; using Jacobi";
}

} // namespace vox::fem
