#include "isxfem/simplex_rule.hpp"

#include <cmath>
#include <stdexcept>

namespace vox::isxfem {
namespace {

double factorial(int n)
{
    double f = 1.0;
    for (int k = 2; k <= n; ++k) f *= k;
    return f;
}

/// Every beta in N^(n+1) with |beta| = m, calling f(beta) (beta[0] is the implicit component).
template <class F> void compositions(int n, int m, F&& f)
{
    std::array<int, 4> beta{};
    auto recurse = [&](auto&& self, int k, int left) -> void {
        if (k == n) {
            beta[static_cast<std::size_t>(n)] = left;
            f(beta);
            return;
        }
        for (int v = 0; v <= left; ++v) {
            beta[static_cast<std::size_t>(k)] = v;
            self(self, k + 1, left - v);
        }
    };
    recurse(recurse, 0, m);
}

SimplexRule grundmann_moeller(int n, int s)
{
    if (s < 0 || s > 12) throw std::invalid_argument("grundmann_moeller: s must be in [0, 12]");
    const int d = 2 * s + 1;
    SimplexRule rule;
    for (int i = 0; i <= s; ++i) {
        const double denominator = d + n - 2 * i;
        const double weight = ((i % 2) ? -1.0 : 1.0) * std::pow(2.0, -2 * s) * std::pow(denominator, d) /
                              (factorial(i) * factorial(d + n - i));
        compositions(n, s - i, [&](const std::array<int, 4>& beta) {
            Eigen::Vector3d x = Eigen::Vector3d::Zero();
            for (int k = 1; k <= n; ++k) x[k - 1] = (2.0 * beta[static_cast<std::size_t>(k)] + 1.0) / denominator;
            rule.points.push_back(x);
            rule.weights.push_back(weight);
        });
    }
    return rule;
}

} // namespace

SimplexRule grundmann_moeller_tetrahedron(int s) { return grundmann_moeller(3, s); }
SimplexRule grundmann_moeller_triangle(int s) { return grundmann_moeller(2, s); }

std::vector<std::array<int, 3>> monomial_exponents(int p)
{
    std::vector<std::array<int, 3>> e;
    for (int degree = 0; degree <= p; ++degree)
        for (int a = degree; a >= 0; --a)
            for (int b = degree - a; b >= 0; --b) e.push_back({a, b, degree - a - b});
    return e;
}

double monomial(const std::array<int, 3>& e, const Eigen::Vector3d& x)
{
    double v = 1.0;
    for (int k = 0; k < 3; ++k)
        for (int j = 0; j < e[static_cast<std::size_t>(k)]; ++j) v *= x[k];
    return v;
}

double reference_tetrahedron_moment(const std::array<int, 3>& e)
{
    return factorial(e[0]) * factorial(e[1]) * factorial(e[2]) / factorial(e[0] + e[1] + e[2] + 3);
}

} // namespace vox::isxfem
