#include "fem/multigrid.hpp"

#include "core/error.hpp"
#include "grid/hex8.hpp"

#include <cmath>
#include <stdexcept>

namespace vox::fem {
namespace {

constexpr int k_sweeps = 2; ///< smoothing sweeps before and after the coarse correction

/// One fine node: its position in index space and a fine element that uses it.
struct FineNode {
    Eigen::Vector3d index_position;
    std::uint32_t element = grid::no_index;
};

/// P from the coarse level `coarse` (nodes numbered densely in order of first use, written to
/// `coarse_dense`) to fine nodes given by `fine`; each fine node takes the trilinear weights of
/// the parent (at `coarse`) of its element.
Eigen::SparseMatrix<double, Eigen::RowMajor> prolongation(const grid::BranchedGrid& grid, int coarse,
                                                          const std::vector<FineNode>& fine,
                                                          std::vector<std::uint32_t>& coarse_dense,
                                                          std::size_t& coarse_count)
{
    const grid::Level& lc = grid.level(coarse);
    coarse_dense.assign(lc.node_users.size(), grid::no_index);
    coarse_count = 0;
    std::vector<Eigen::Triplet<double>> t;
    t.reserve(fine.size() * 24);
    const double size = static_cast<double>(1 << coarse);
    for (std::size_t n = 0; n < fine.size(); ++n) {
        const std::uint32_t parent = lc.parent[fine[n].element];
        const grid::Element& e = lc.elements[parent];
        const Eigen::Vector3d local =
            (fine[n].index_position - grid::BranchedGrid::cell_corner_index(e.cell, coarse, 0)) / size;
        for (int c = 0; c < 8; ++c) {
            const double w = grid::hex8_shape(c, local);
            if (w == 0.0) continue;
            std::uint32_t& id = coarse_dense[e.nodes[c]];
            if (id == grid::no_index) id = static_cast<std::uint32_t>(coarse_count++);
            for (int i = 0; i < 3; ++i) t.emplace_back(static_cast<int>(3 * n) + i, static_cast<int>(3 * id) + i, w);
        }
    }
    Eigen::SparseMatrix<double, Eigen::RowMajor> p(static_cast<Eigen::Index>(3 * fine.size()),
                                                   static_cast<Eigen::Index>(3 * coarse_count));
    p.setFromTriplets(t.begin(), t.end());
    return p;
}

} // namespace

Multigrid::Multigrid(const grid::BranchedGrid& grid, const HexModel& model, int coarsest_level, std::size_t direct_dofs)
{
    // The model's own nodes, each with one element that uses it.
    std::vector<FineNode> fine(model.node_count());
    const int level = model.level();
    for (const HexElement& el : model.elements()) {
        const grid::Coord cell = level == 0 ? grid.voxels().coord(el.grid_element)
                                            : grid.level(level).elements[el.grid_element].cell;
        for (int c = 0; c < 8; ++c) {
            FineNode& f = fine[el.dof_node[c]];
            if (f.element != grid::no_index) continue;
            f.element = el.grid_element;
            f.index_position = grid::BranchedGrid::cell_corner_index(cell, level, c);
        }
    }
    std::size_t dofs = 3 * fine.size();
    for (int coarse = level + 1; coarse <= std::min(coarsest_level, grid.max_level()) && dofs > direct_dofs; ++coarse) {
        std::vector<std::uint32_t> dense;
        std::size_t count = 0;
        m_prolongation.push_back(prolongation(grid, coarse, fine, dense, count));
        dofs = 3 * count;
        // The coarse nodes become the fine nodes of the next level.
        std::vector<FineNode> next(count);
        const grid::Level& lc = grid.level(coarse);
        for (std::uint32_t e = 0; e < lc.elements.size(); ++e) {
            if (!lc.elements[e].alive) continue;
            for (int c = 0; c < 8; ++c) {
                const std::uint32_t id = dense[lc.elements[e].nodes[c]];
                if (id == grid::no_index || next[id].element != grid::no_index) continue;
                next[id].element = e;
                next[id].index_position = grid::BranchedGrid::cell_corner_index(lc.elements[e].cell, coarse, c);
            }
        }
        fine = std::move(next);
    }
}

void Multigrid::update(const Matrix* a, const std::vector<unsigned char>& fixed, const std::vector<Eigen::Quaterniond>&)
{
    if (!a) throw std::logic_error("Multigrid::update: needs the assembled matrix");
    m_matrix.resize(level_count());
    m_inverse_diagonal.resize(level_count());
    m_matrix[0] = *a;
    for (std::size_t k = 0; k + 1 < level_count(); ++k) {
        Eigen::SparseMatrix<double, Eigen::RowMajor> p = m_prolongation[k];
        if (k == 0) // held fine dofs take no coarse correction
            for (Eigen::Index row = 0; row < p.outerSize(); ++row)
                if (fixed[static_cast<std::size_t>(row)])
                    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(p, row); it; ++it) it.valueRef() = 0.0;
        Matrix coarse = Matrix(p.transpose() * m_matrix[k] * p);
        // Coarse dofs that only reach held fine dofs: identity, so the level stays definite.
        for (Eigen::Index i = 0; i < coarse.rows(); ++i)
            if (coarse.coeff(i, i) <= 0.0) coarse.coeffRef(i, i) = 1.0;
        m_matrix[k + 1] = std::move(coarse);
        if (k == 0) m_prolongation[0] = std::move(p); // keep the masked version for the cycle
    }
    // l1-Jacobi smoothing: the inverse of each row's absolute sum. Unlike damped Jacobi it
    // converges for any symmetric positive definite matrix (hexahedra with consistent mass have
    // D^-1 A eigenvalues above 3, beyond the reach of a fixed damping weight).
    for (std::size_t k = 0; k < level_count(); ++k) {
        Eigen::VectorXd sums = Eigen::VectorXd::Zero(m_matrix[k].rows());
        for (Eigen::Index row = 0; row < m_matrix[k].outerSize(); ++row)
            for (Matrix::InnerIterator it(m_matrix[k], row); it; ++it) sums[row] += std::abs(it.value());
        m_inverse_diagonal[k] = sums.cwiseInverse();
    }
    m_coarsest.compute(Eigen::SparseMatrix<double>(m_matrix.back()));
    if (m_coarsest.info() != Eigen::Success) throw InputError("multigrid: the coarsest system is not definite");
}

void Multigrid::apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const { cycle(0, r, z); }

void Multigrid::cycle(std::size_t k, const Eigen::VectorXd& r, Eigen::VectorXd& z) const
{
    if (k + 1 == level_count()) {
        z = m_coarsest.solve(r);
        return;
    }
    const Matrix& a = m_matrix[k];
    const Eigen::VectorXd& dinv = m_inverse_diagonal[k];
    z = dinv.cwiseProduct(r);
    for (int s = 1; s < k_sweeps; ++s) z += dinv.cwiseProduct(r - a * z);
    const Eigen::VectorXd coarse_r = m_prolongation[k].transpose() * (r - a * z);
    Eigen::VectorXd coarse_z;
    cycle(k + 1, coarse_r, coarse_z);
    z += m_prolongation[k] * coarse_z;
    for (int s = 0; s < k_sweeps; ++s) z += dinv.cwiseProduct(r - a * z);
}

} // namespace vox::fem
