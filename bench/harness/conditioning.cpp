#include "bench/harness/conditioning.hpp"

#include "core/atomic_file.hpp"
#include "isxfem/plane_cut_system.hpp"

#include <Eigen/Eigenvalues>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <sstream>

namespace vox::bench {
namespace {

constexpr double k_h = 0.005;          ///< element size, m
constexpr int k_cells = 12;            ///< along the bar; 3 x 3 across
constexpr double k_dt = 0.01;          ///< s, the scenes' default
constexpr double k_youngs = 1e5, k_poisson = 0.3, k_density = 1500.0; // clay
constexpr double k_lambda = 1e-3, k_threshold = 1e-4; ///< the regularisation measured (isxfem/xfem_solver.hpp)

/// lambda_max / lambda_min of the symmetric positive (semi)definite s; infinity when the smallest
/// eigenvalue is not positive.
double condition_number(const Eigen::MatrixXd& s)
{
    const Eigen::VectorXd e = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(s, Eigen::EigenvaluesOnly).eigenvalues();
    return e.minCoeff() > 0.0 ? e.maxCoeff() / e.minCoeff() : INFINITY;
}

/// The condition numbers of s: plain, scaled by t (T s T), by u, and Jacobi-scaled.
std::array<double, 4> conditions(const Eigen::MatrixXd& s, const Eigen::VectorXd& t, const Eigen::VectorXd& u)
{
    const Eigen::VectorXd jacobi = s.diagonal().cwiseSqrt().cwiseInverse();
    return {condition_number(s), condition_number(t.asDiagonal() * s * t.asDiagonal()), condition_number(u.asDiagonal() * s * u.asDiagonal()),
            condition_number(jacobi.asDiagonal() * s * jacobi.asDiagonal())};
}

ConditioningRow measure(const isxfem::TetMesh& bar, double theta, double k, const std::string& method)
{
    const grid::Lame lame = grid::lame_from_young_poisson(k_youngs, k_poisson);
    // theta = 0 stands for the uncut bar: the plane lies beyond it.
    const isxfem::PlaneCut cut{Eigen::Vector3d::UnitX(), theta > 0.0 ? (k_cells / 2 + theta) * k_h : -1.0};
    const isxfem::PlaneCutSystem s = isxfem::assemble_plane_cut(bar, cut, k, lame, k_density);
    // Free dofs: all but the standard dofs of the nodes at both ends.
    std::vector<Eigen::Index> free;
    for (std::size_t d = 0; d < s.dofs(); ++d) {
        const std::size_t node = d / 3;
        const bool held = node < bar.nodes.size() && (bar.nodes[node].x() < 1e-9 || bar.nodes[node].x() > k_cells * k_h - 1e-9);
        if (!held) free.push_back(static_cast<Eigen::Index>(d));
    }
    const auto n = static_cast<Eigen::Index>(free.size());
    const Eigen::MatrixXd k_full(s.stiffness), m_full(s.mass);
    Eigen::MatrixXd kf(n, n), af(n, n);
    Eigen::VectorXd t(n), u(n);
    ConditioningRow row;
    row.method = method;
    row.theta = theta;
    row.dofs = free.size();
    for (Eigen::Index i = 0; i < n; ++i) {
        const double ratio = s.volume_ratio[static_cast<std::size_t>(free[static_cast<std::size_t>(i)])];
        row.min_volume_ratio = std::min(row.min_volume_ratio, ratio);
        t[i] = 1.0 / std::sqrt(ratio);
        u[i] = 1.0 / std::sqrt(s.weighted_ratio[static_cast<std::size_t>(free[static_cast<std::size_t>(i)])]);
        for (Eigen::Index j = 0; j < n; ++j) {
            kf(i, j) = k_full(free[static_cast<std::size_t>(i)], free[static_cast<std::size_t>(j)]);
            af(i, j) = m_full(free[static_cast<std::size_t>(i)], free[static_cast<std::size_t>(j)]) + k_dt * k_dt * kf(i, j);
        }
    }
    row.k = conditions(kf, t, u);
    row.a = conditions(af, t, u);
    double standard = 0.0;
    int count = 0;
    for (Eigen::Index i = 0; i < n; ++i)
        if (static_cast<std::size_t>(free[static_cast<std::size_t>(i)]) < 3 * bar.nodes.size()) {
            standard += af(i, i);
            ++count;
        }
    Eigen::MatrixXd regularised = af;
    for (Eigen::Index i = 0; i < n; ++i)
        if (s.volume_ratio[static_cast<std::size_t>(free[static_cast<std::size_t>(i)])] < k_threshold) {
            regularised(i, i) += k_lambda * standard / count;
            ++row.regularised_dofs;
        }
    const std::array<double, 4> c = conditions(regularised, t, u);
    row.regularised = {c[0], c[3]};
    return row;
}

std::string number(double v) { return std::isfinite(v) ? (std::ostringstream() << std::scientific << std::setprecision(2) << v).str() : "singular"; }

} // namespace

std::vector<ConditioningRow> run_conditioning()
{
    const isxfem::TetMesh bar = isxfem::cube_lattice({k_cells, 3, 3}, k_h);
    std::vector<ConditioningRow> rows{measure(bar, 0.0, 0.0, "uncut")};
    for (const auto& [k, method] : {std::pair{0.0, "XFEM (k = 0)"}, std::pair{0.1, "Is-XFEM (k = 0.1)"}})
        for (double theta : {1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6}) {
            rows.push_back(measure(bar, theta, k, method));
            std::fprintf(stderr, "%s, theta %.0e done\n", method, theta);
        }
    return rows;
}

void write_conditioning(const std::filesystem::path& dir, const std::vector<ConditioningRow>& rows)
{
    std::ostringstream md;
    md << "# Conditioning of cut systems (`voxsculpt bench conditioning`)\n\n"
          "A bar of 12 x 3 x 3 cubes of 5 mm, each split into six tetrahedra (E 100 kPa, nu 0.3, "
          "1500 kg/m^3), held at both ends, cut through by the plane x = 30 mm + theta h (h = 5 mm): "
          "condition numbers over the free dofs of K and of A = M + dt^2 K (consistent mass, dt 0.01 s). "
          "Plain; with the volume-ratio preconditioner T = diag(1 / sqrt(v)) of the Is-XFEM paper "
          "(equations 15 to 17; v the share of an enriched node's support across the cut, 1 for "
          "standard dofs); with the same T built from the enrichment-weighted ratio "
          "w = int (psi N)^2 / int N^2; and with Jacobi scaling diag(1 / sqrt(S_ii)). \"singular\": the "
          "smallest eigenvalue did not come out positive in double precision. Last, A regularised as the "
          "paper's section 4.3.2 does: A + lambda I on the dofs whose volume ratio is below 1e-4 (how many: "
          "\"regularised dofs\"), lambda 1e-3 of the mean diagonal of the standard dofs, plain and "
          "Jacobi-scaled.\n\n"
          "| method | theta | free dofs | min volume ratio | K | T K T | T_w K T_w | Jacobi K | A | T A T | T_w A T_w | Jacobi A | "
          "regularised dofs | A + lambda I | Jacobi (A + lambda I) |\n"
          "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const ConditioningRow& r : rows) {
        md << "| " << r.method << " | " << (r.theta > 0.0 ? number(r.theta) : "-") << " | " << r.dofs << " | " << number(r.min_volume_ratio);
        for (double c : r.k) md << " | " << number(c);
        for (double c : r.a) md << " | " << number(c);
        md << " | " << r.regularised_dofs;
        for (double c : r.regularised) md << " | " << number(c);
        md << " |\n";
    }
    // The same rows as data (infinite condition numbers, "singular" above, as null).
    auto finite_or_null = [](double c) { return std::isfinite(c) ? nlohmann::json(c) : nlohmann::json(); };
    nlohmann::json data = nlohmann::json::array();
    for (const ConditioningRow& r : rows) {
        nlohmann::json k = nlohmann::json::array(), a = nlohmann::json::array(), reg = nlohmann::json::array();
        for (double c : r.k) k.push_back(finite_or_null(c));
        for (double c : r.a) a.push_back(finite_or_null(c));
        for (double c : r.regularised) reg.push_back(finite_or_null(c));
        data.push_back({{"method", r.method}, {"theta", r.theta}, {"free_dofs", r.dofs}, {"min_volume_ratio", r.min_volume_ratio},
                        {"k_plain_volume_ratio_weighted_jacobi", k}, {"a_plain_volume_ratio_weighted_jacobi", a},
                        {"regularised_dofs", r.regularised_dofs}, {"a_regularised_plain_jacobi", reg}});
    }
    std::filesystem::create_directories(dir);
    write_atomically(dir / "conditioning.md", [&](const std::filesystem::path& tmp) { std::ofstream(tmp) << md.str(); });
    write_atomically(dir / "conditioning.json", [&](const std::filesystem::path& tmp) { std::ofstream(tmp) << data.dump(1) << '\n'; });
    std::printf("%s\nwrote %s and conditioning.json\n", md.str().c_str(), (dir / "conditioning.md").c_str());
}

} // namespace vox::bench
