#include "shape/global_step.hpp"

#include <stdexcept>

namespace vox::shape {

void GlobalStep::prepare(const ClusterLevel& level, const std::vector<double>& scale, const std::vector<double>& inertia,
                         const std::vector<unsigned char>& fixed)
{
    if (m_factor[0] && scale == m_scale && inertia == m_inertia && fixed == m_fixed) return;
    const auto n = static_cast<Eigen::Index>(inertia.size());
    std::vector<Eigen::Triplet<double>> t;
    t.reserve(level.particle.size() * 8 + inertia.size());
    double diagonal = 0.0;
    for (std::size_t c = 0; c < level.size(); ++c) {
        const std::uint32_t begin = level.start[c], end = level.start[c + 1];
        const double s = scale.empty() ? 1.0 : scale[c];
        double total = 0.0;
        for (std::uint32_t m = begin; m < end; ++m) total += s * level.weight[m];
        for (std::uint32_t a = begin; a < end; ++a) {
            const double wa = s * level.weight[a];
            t.emplace_back(level.particle[a], level.particle[a], wa);
            diagonal += wa;
            for (std::uint32_t b = begin; b < end; ++b)
                t.emplace_back(level.particle[a], level.particle[b], -wa * s * level.weight[b] / total);
        }
    }
    // Statically a piece no hold reaches could slide freely: a floor of 1e-9 of the mean diagonal
    // keeps it where it is instead of making the matrix singular.
    const double floor = 1e-9 * diagonal / static_cast<double>(std::max<Eigen::Index>(n, 1));
    for (Eigen::Index j = 0; j < n; ++j) t.emplace_back(j, j, std::max(inertia[static_cast<std::size_t>(j)], floor));
    m_full.resize(n, n);
    m_full.setFromTriplets(t.begin(), t.end());
    m_full.makeCompressed();

    for (std::size_t axis = 0; axis < 3; ++axis) {
        m_held[axis].assign(inertia.size(), 0);
        for (std::size_t j = 0; j < inertia.size(); ++j) m_held[axis][j] = fixed[3 * j + axis];
    }
    for (std::size_t axis = 0; axis < 3; ++axis) {
        const std::size_t same = axis > 0 && m_held[axis] == m_held[0] ? 0 : axis == 2 && m_held[2] == m_held[1] ? 1 : axis;
        if (same != axis) {
            m_factor[axis] = m_factor[same];
            continue;
        }
        Matrix a = m_full;
        for (Eigen::Index col = 0; col < a.outerSize(); ++col)
            for (Matrix::InnerIterator it(a, col); it; ++it)
                if (m_held[axis][static_cast<std::size_t>(it.row())] || m_held[axis][static_cast<std::size_t>(col)])
                    it.valueRef() = it.row() == col ? 1.0 : 0.0;
        auto factor = std::make_shared<Eigen::SimplicialLDLT<Matrix>>(a);
        if (factor->info() != Eigen::Success) throw std::runtime_error("shape matching: the global step's matrix could not be factored");
        m_factor[axis] = std::move(factor);
        ++m_factorizations;
    }
    m_scale = scale;
    m_inertia = inertia;
    m_fixed = fixed;
}

void GlobalStep::solve(const std::vector<Eigen::Vector3d>& rhs, std::vector<Eigen::Vector3d>& out) const
{
    const auto n = static_cast<Eigen::Index>(rhs.size());
    out.resize(rhs.size());
    // The axes sharing a factor are solved together (one pass over the factor for up to three
    // right-hand sides: the back-substitutions are most of a step's time).
    Eigen::MatrixX3d b(n, 3);
    for (Eigen::Index j = 0; j < n; ++j)
        for (Eigen::Index axis = 0; axis < 3; ++axis)
            b(j, axis) = m_held[static_cast<std::size_t>(axis)][static_cast<std::size_t>(j)] ? 0.0 : rhs[static_cast<std::size_t>(j)][axis];
    Eigen::MatrixX3d x(n, 3);
    if (m_factor[1] == m_factor[0] && m_factor[2] == m_factor[0]) {
        x = m_factor[0]->solve(b);
    } else {
        for (Eigen::Index axis = 0; axis < 3; ++axis) x.col(axis) = m_factor[static_cast<std::size_t>(axis)]->solve(b.col(axis));
    }
    for (Eigen::Index j = 0; j < n; ++j) out[static_cast<std::size_t>(j)] = x.row(j).transpose();
}

void GlobalStep::multiply_full(const std::vector<Eigen::Vector3d>& u, std::vector<Eigen::Vector3d>& out) const
{
    const auto n = static_cast<Eigen::Index>(u.size());
    out.resize(u.size());
    for (std::size_t axis = 0; axis < 3; ++axis) {
        Eigen::VectorXd v(n);
        for (Eigen::Index j = 0; j < n; ++j) v[j] = u[static_cast<std::size_t>(j)][static_cast<Eigen::Index>(axis)];
        const Eigen::VectorXd w = m_full * v;
        for (Eigen::Index j = 0; j < n; ++j) out[static_cast<std::size_t>(j)][static_cast<Eigen::Index>(axis)] = w[j];
    }
}

void GlobalStep::multiply(const std::vector<Eigen::Vector3d>& u, std::vector<Eigen::Vector3d>& out) const
{
    const auto n = static_cast<Eigen::Index>(u.size());
    out.assign(u.size(), Eigen::Vector3d::Zero());
    for (std::size_t axis = 0; axis < 3; ++axis) {
        Eigen::VectorXd v(n);
        for (Eigen::Index j = 0; j < n; ++j)
            v[j] = m_held[axis][static_cast<std::size_t>(j)] ? 0.0 : u[static_cast<std::size_t>(j)][static_cast<Eigen::Index>(axis)];
        const Eigen::VectorXd w = m_full * v;
        for (Eigen::Index j = 0; j < n; ++j)
            if (!m_held[axis][static_cast<std::size_t>(j)]) out[static_cast<std::size_t>(j)][static_cast<Eigen::Index>(axis)] = w[j];
    }
}

} // namespace vox::shape
