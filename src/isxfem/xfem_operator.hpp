#pragma once
// The corotated system of an XFEM model at its current state, A = scale_m M + scale_k K(x), with
// identity rows and columns for held dofs: what each step of the implicit solver needs (elastic
// forces, rotations, the matrix, products with it).
//
// A is assembled every step, because a linear tetrahedron is cheap to assemble and expensive to
// apply element by element: its 3 x 3 block between corners a and b turned by R is
//   V [lambda g'_a g'_b^T + mu (g'_b g'_a^T + (g_a . g_b) I)],   g' = R g,
// two outer products, while an element-wise product costs about 130 flops per tetrahedron per
// CG iteration against about 80 for its share of the assembled rows (measured: 1.3 against
// 0.35 ms a product on 9,720 tetrahedra). A cut tetrahedron adds each region's stiffness turned
// by that region's rotation.
//
// Every loop runs on all threads without two threads adding to one entry: elements write their
// forces to their own slots, which each dof block then gathers, and the matrix is filled row block
// by row block, each from the elements that touch it.
//
// The mass of every element is a scalar per pair of dof blocks times the 3 x 3 identity (the
// enrichment multiplies the shape functions, not the axes), kept as one block-scalar sparse matrix.

#include "isxfem/xfem_model.hpp"

#include "fem/pair_contact.hpp"
#include "fem/preconditioner.hpp"
#include "fem/volume_correction.hpp"

#include <Eigen/Geometry>
#include <Eigen/SparseCore>

#include <array>
#include <vector>

namespace vox::isxfem {

class XfemOperator {
public:
    explicit XfemOperator(const XfemModel& model);

    /// After the model was cut: sizes, the matrix pattern and the mass for the grown set of dof
    /// blocks. Newly cut tetrahedra turn both sides as they turned whole. Returns the dof blocks
    /// that existed before and whose rows changed: the old enriched blocks newly cut tetrahedra
    /// share (a crack growing); the nodes' own rows stay as they were (a cut tetrahedron's standard
    /// part is the whole one's).
    std::vector<std::uint32_t> model_changed();

    /// Rotations (each warm-started from the last), elastic forces and the matrix at the state x
    /// (positions of nodes, then enriched displacements); `fixed` flags held dofs.
    void update(const std::vector<Eigen::Vector3d>& x, const std::vector<unsigned char>& fixed, double scale_m, double scale_k);

    /// Adds `relative` times the mean diagonal of the free standard dofs to the diagonal of the
    /// free dofs of `blocks` (the regularisation A + lambda I of the sculpting paper, section
    /// 4.3.2), until the next update(). Returns what was added.
    double add_to_diagonal(const std::vector<std::uint32_t>& blocks, double relative);

    /// Adds w_a w_b m to the 3 x 3 blocks of the matrix between element e's dof blocks a and b
    /// (its local numbering: nodes, then enriched): the stiffness m of a point load acting through
    /// the weights w. Held dofs keep their identity rows and columns; until the next update().
    void add_point_stiffness(std::size_t e, const std::array<double, k_max_blocks>& w, const Eigen::Matrix3d& m);
    /// Adds `scale` times a pair contact's stiffness when the pattern joins its blocks
    /// (fem::add_to_matrix; held dofs kept); until the next update(). Returns whether it did.
    bool add_pair_stiffness(const fem::PairContact& p, double scale) { return fem::add_to_matrix(p, scale, m_fixed, m_matrix); }

    /// out = A p, the matrix of the last update().
    void multiply(const Eigen::VectorXd& p, Eigen::VectorXd& out) const;
    /// out = M p.
    void mass_multiply(const Eigen::VectorXd& p, Eigen::VectorXd& out) const;

    [[nodiscard]] const fem::SystemMatrix& matrix() const { return m_matrix; }
    /// The elastic forces R K (R^T x - X) of the last update(), N.
    [[nodiscard]] const Eigen::VectorXd& internal_force() const { return m_force; }
    [[nodiscard]] Eigen::VectorXd diagonal() const { return m_matrix.diagonal(); }
    /// Per element its rotation, and per region for a cut one (XfemElement::region_at; with one
    /// cut, region 0 is phi < 0).
    [[nodiscard]] const std::array<Eigen::Quaterniond, 1u << k_max_cuts>& rotation(std::size_t e) const { return m_rotation[e]; }

    /// Per dof block the mean rotation of what turns it: a node's whole tetrahedra and its own region
    /// of the cut ones; an enriched block (the jump across a crack) the region across that crack
    /// from its node. What a warped preconditioner follows (fem::JumpBlock).
    void block_rotations(std::vector<Eigen::Quaterniond>& out) const;

private:
    void build_pattern();
    void fill_row(std::size_t block, double scale_m, double scale_k);

    const XfemModel& m_model;
    std::vector<std::array<Eigen::Quaterniond, 1u << k_max_cuts>> m_rotation; ///< per element, per region
    std::vector<std::array<Eigen::Matrix3d, 1u << k_max_cuts>> m_r;           ///< the same as matrices
    std::vector<Eigen::Matrix<double, 3, 4>> m_turned_gradient; ///< per whole element: R g_c by corner
    std::vector<fem::VolumeHessian> m_volume_hessian;           ///< per whole element: of its volume correction
    std::vector<unsigned char> m_cut_count; ///< per element: the cuts its rotations know of
    std::vector<std::array<double, 2>> m_lame_volume; ///< per element: V lambda, V mu
    std::vector<std::uint32_t> m_slot_start;          ///< per element: first of its 3 per dof block force values in m_slots
    std::vector<double> m_slots;
    /// Per block: its elements, as (element, corner) pairs, and where each of that element's
    /// blocks sits in the block's row of the block pattern.
    std::vector<std::uint32_t> m_touch_start;
    std::vector<std::array<std::uint32_t, 2>> m_touch;
    std::vector<std::uint32_t> m_rank_start, m_rank;
    Eigen::SparseMatrix<double, Eigen::RowMajor> m_block_mass; ///< blocks x blocks, kg
    fem::SystemMatrix m_matrix;
    std::vector<unsigned char> m_fixed;
    Eigen::VectorXd m_force;
};

} // namespace vox::isxfem
