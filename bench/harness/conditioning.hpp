#pragma once
// voxsculpt bench conditioning: how well conditioned the Is-XFEM systems stay as a cut passes
// ever closer to a node plane. A bar of 12 x 3 x 3 cubes of 5 mm (six tetrahedra each), held at
// both ends so each piece stays held after a through-cut, is cut by the plane x = 30 mm + theta h
// (h = 5 mm), theta = 1e-1 to 1e-6, with k = 0 (XFEM) and k = 0.1 (Is-XFEM). For each: the
// condition numbers of K and of A = M + dt^2 K over the free dofs, plain, with the paper's
// volume-ratio preconditioner T = diag(1 / sqrt(v)) (equations 15 to 17), with the same built
// from the enrichment-weighted ratio (plane_cut_system.hpp) and, for comparison, with Jacobi
// scaling diag(1 / sqrt(A_ii)); and A regularised as the paper's section 4.3.2 does (A + lambda I
// on the enriched dofs whose volume ratio is below 1e-4, lambda 1e-3 of the mean diagonal of the
// standard dofs), plain and Jacobi-scaled.

#include <array>
#include <filesystem>
#include <string>
#include <vector>

namespace vox::bench {

struct ConditioningRow {
    std::string method;        ///< "uncut", "XFEM (k = 0)", "Is-XFEM (k = 0.1)"
    double theta = 0.0;        ///< cut distance from the node plane, in element sizes (0: uncut)
    std::size_t dofs = 0;      ///< free dofs
    double min_volume_ratio = 1.0;
    /// Condition numbers of K and of M + dt^2 K: plain, volume-ratio T, weighted-ratio T, Jacobi.
    std::array<double, 4> k{}, a{};
    /// Condition numbers of A + lambda I (on the dofs below the threshold): plain, Jacobi.
    std::array<double, 2> regularised{};
    std::size_t regularised_dofs = 0;
};

[[nodiscard]] std::vector<ConditioningRow> run_conditioning();

/// Writes DIR/conditioning.md (the table and how it was made) and prints it.
void write_conditioning(const std::filesystem::path& dir, const std::vector<ConditioningRow>& rows);

} // namespace vox::bench
