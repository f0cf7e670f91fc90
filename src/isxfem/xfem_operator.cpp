#include "isxfem/xfem_operator.hpp"

#include "fem/corotation.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <stdexcept>

namespace vox::isxfem {
namespace {

/// V sigma(sym h): the isotropic linear stress of the displacement gradient h, times the volume
/// (`lame_volume`: V lambda, V mu).
Eigen::Matrix3d stress(const Eigen::Matrix3d& h, const std::array<double, 2>& lame_volume)
{
    const Eigen::Matrix3d strain = 0.5 * (h + h.transpose());
    Eigen::Matrix3d s = 2.0 * lame_volume[1] * strain;
    s.diagonal().array() += lame_volume[0] * strain.trace();
    return s;
}

/// sum_c v_c g_c^T over the corners of a tetrahedron.
Eigen::Matrix3d gradient_of(const std::array<Eigen::Vector3d, 4>& v, const TetGeometry& g)
{
    Eigen::Matrix3d out = v[0] * g.gradient.row(0);
    for (int c = 1; c < 4; ++c) out.noalias() += v[static_cast<std::size_t>(c)] * g.gradient.row(c);
    return out;
}

/// The linear field of region `pattern` of a cut element (exact for k = 0, the linear part for
/// k > 0), whose gradient gives the region's rotation.
std::array<Eigen::Vector3d, 4> region_field(const XfemElement& el, const std::vector<Eigen::Vector3d>& x, unsigned pattern)
{
    std::array<Eigen::Vector3d, 4> p{};
    for (std::size_t c = 0; c < 4; ++c) p[c] = el.region_node(c, pattern, x);
    return p;
}

template <class F> void parallel(std::size_t n, F&& f)
{
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 128), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) f(i);
    });
}

} // namespace

XfemOperator::XfemOperator(const XfemModel& model) : m_model(model)
{
    const auto& elements = model.elements();
    m_lame_volume.resize(elements.size());
    for (std::size_t e = 0; e < elements.size(); ++e) {
        const grid::Lame& lame = model.materials()[elements[e].material].lame;
        m_lame_volume[e] = {elements[e].geometry.volume * lame.lambda, elements[e].geometry.volume * lame.mu};
    }
    model_changed();
}

std::vector<std::uint32_t> XfemOperator::model_changed()
{
    const auto& elements = m_model.elements();
    const std::size_t blocks = m_model.block_count();
    const auto old_blocks = static_cast<std::uint32_t>(m_block_mass.rows());
    std::vector<std::uint32_t> changed;
    const Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
    const Eigen::Matrix3d i3 = Eigen::Matrix3d::Identity();
    m_rotation.resize(elements.size(), {q, q, q, q});
    m_r.resize(elements.size(), {i3, i3, i3, i3});
    m_turned_gradient.resize(elements.size());
    m_volume_hessian.resize(elements.size());
    m_cut_count.resize(elements.size(), 0);
    m_slot_start.assign(elements.size() + 1, 0);
    std::vector<std::uint32_t> count(blocks + 1, 0);
    for (std::size_t e = 0; e < elements.size(); ++e) {
        const XfemElement& el = elements[e];
        if (el.cuts.size() > m_cut_count[e]) { // newly cut: its new regions start from the rotation of the one they split
            const unsigned before = 1u << m_cut_count[e];
            for (unsigned p = before; p < (1u << el.cuts.size()); ++p) {
                m_rotation[e][p] = m_rotation[e][p % before];
                m_r[e][p] = m_r[e][p % before];
            }
            m_cut_count[e] = static_cast<unsigned char>(el.cuts.size());
            for (const ElementCut& cut : el.cuts)
                for (std::uint32_t b : cut.enriched)
                    if (b < old_blocks) changed.push_back(b);
        }
        const std::size_t n = el.block_count();
        m_slot_start[e + 1] = m_slot_start[e] + static_cast<std::uint32_t>(3 * n);
        for (std::size_t a = 0; a < n; ++a) ++count[el.block(a) + 1];
    }
    for (std::size_t b = 0; b < blocks; ++b) count[b + 1] += count[b];
    m_touch_start = count;
    m_touch.resize(count[blocks]);
    for (std::size_t e = 0; e < elements.size(); ++e)
        for (std::size_t a = 0; a < elements[e].block_count(); ++a)
            m_touch[count[elements[e].block(a)]++] = {static_cast<std::uint32_t>(e), static_cast<std::uint32_t>(a)};
    // Each block's neighbours (itself always, so the matrix keeps a diagonal even for a block no
    // element touches), row by row on all threads.
    std::vector<std::vector<std::uint32_t>> neighbours(blocks);
    parallel(blocks, [&](std::size_t b) {
        auto& list = neighbours[b];
        list.push_back(static_cast<std::uint32_t>(b));
        for (std::uint32_t t = m_touch_start[b]; t < m_touch_start[b + 1]; ++t) {
            const XfemElement& el = elements[m_touch[t][0]];
            for (std::size_t c = 0; c < el.block_count(); ++c) list.push_back(el.block(c));
        }
        std::sort(list.begin(), list.end());
        list.erase(std::unique(list.begin(), list.end()), list.end());
    });
    m_block_mass.resize(static_cast<Eigen::Index>(blocks), static_cast<Eigen::Index>(blocks));
    int* outer = m_block_mass.outerIndexPtr();
    outer[0] = 0;
    for (std::size_t b = 0; b < blocks; ++b) outer[b + 1] = outer[b] + static_cast<int>(neighbours[b].size());
    m_block_mass.resizeNonZeros(outer[blocks]);
    m_rank_start.assign(m_touch.size() + 1, 0);
    for (std::size_t t = 0; t < m_touch.size(); ++t) m_rank_start[t + 1] = m_rank_start[t] + static_cast<std::uint32_t>(elements[m_touch[t][0]].block_count());
    m_rank.resize(m_rank_start.back());
    // The mass row by row, and where each element's blocks sit in the rows of the blocks they touch.
    parallel(blocks, [&](std::size_t b) {
        int* inner = m_block_mass.innerIndexPtr() + outer[b];
        double* values = m_block_mass.valuePtr() + outer[b];
        const auto& list = neighbours[b];
        std::copy(list.begin(), list.end(), inner);
        std::fill(values, values + list.size(), 0.0);
        for (std::uint32_t t = m_touch_start[b]; t < m_touch_start[b + 1]; ++t) {
            const XfemElement& el = elements[m_touch[t][0]];
            const auto a = static_cast<Eigen::Index>(3 * m_touch[t][1]);
            for (std::size_t c = 0; c < el.block_count(); ++c) {
                const auto rank = static_cast<std::uint32_t>(std::lower_bound(list.begin(), list.end(), el.block(c)) - list.begin());
                m_rank[m_rank_start[t] + c] = rank;
                values[rank] += el.mass(a, static_cast<Eigen::Index>(3 * c));
            }
        }
    });
    build_pattern();
    m_slots.resize(m_slot_start.back());
    m_force = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(3 * blocks));
    return changed;
}

void XfemOperator::build_pattern()
{
    // Block row A holds, for each neighbour B in the order of the block mass's row, three columns;
    // an entry of A's dof i and B's dof j sits at outer[3A + i] + 3 rank(A, B) + j.
    const auto blocks = m_block_mass.rows();
    const int* block_outer = m_block_mass.outerIndexPtr();
    const int* block_inner = m_block_mass.innerIndexPtr();
    m_matrix.resize(3 * blocks, 3 * blocks);
    m_matrix.resizeNonZeros(9 * m_block_mass.nonZeros());
    int* outer = m_matrix.outerIndexPtr();
    for (Eigen::Index b = 0; b < blocks; ++b) {
        const int width = 3 * (block_outer[b + 1] - block_outer[b]);
        for (int i = 0; i < 3; ++i) outer[3 * b + i] = 9 * block_outer[b] + i * width;
    }
    outer[3 * blocks] = 9 * block_outer[blocks];
    int* inner = m_matrix.innerIndexPtr();
    parallel(static_cast<std::size_t>(blocks), [&](std::size_t b) {
        for (std::size_t i = 0; i < 3; ++i) {
            int position = outer[3 * b + i];
            for (int k = block_outer[b]; k < block_outer[b + 1]; ++k)
                for (int j = 0; j < 3; ++j) inner[position++] = 3 * block_inner[k] + j;
        }
    });
}

void XfemOperator::update(const std::vector<Eigen::Vector3d>& x, const std::vector<unsigned char>& fixed, double scale_m,
                          double scale_k)
{
    const auto& elements = m_model.elements();
    const auto& rest = m_model.mesh().nodes;
    m_fixed = fixed;
    parallel(elements.size(), [&](std::size_t e) {
        const XfemElement& el = elements[e];
        double* force = &m_slots[m_slot_start[e]];
        if (!el.is_cut()) {
            // F = I + grad(x - X): from displacements, so an element at rest has exactly no strain.
            std::array<Eigen::Vector3d, 4> displacement{};
            for (std::size_t c = 0; c < 4; ++c) displacement[c] = x[el.node[c]] - rest[el.node[c]];
            const Eigen::Matrix3d f = Eigen::Matrix3d::Identity() + gradient_of(displacement, el.geometry);
            fem::extract_rotation(f, m_rotation[e][0]);
            const Eigen::Matrix3d r = m_r[e][0] = m_rotation[e][0].toRotationMatrix();
            // With the volume correction of a squeezed element (fem/volume_correction.hpp).
            const fem::VolumeCorrection volume = fem::volume_correction(f, r, m_lame_volume[e][0]);
            m_volume_hessian[e] = volume.hessian;
            const Eigen::Matrix3d s = r * stress(r.transpose() * f - Eigen::Matrix3d::Identity(), m_lame_volume[e]) + volume.gradient;
            for (Eigen::Index c = 0; c < 4; ++c) Eigen::Map<Eigen::Vector3d>(force + 3 * c) = s * el.geometry.gradient.row(c).transpose();
            m_turned_gradient[e].noalias() = r * el.geometry.gradient.transpose();
            return;
        }
        // Every region's rotation (empty ones too: a block's rotation may ask for them), then
        // each region's stiffness in its own frame.
        for (unsigned p = 0; p < (1u << el.cuts.size()); ++p) {
            fem::extract_rotation(gradient_of(region_field(el, x, p), el.geometry), m_rotation[e][p]);
            m_r[e][p] = m_rotation[e][p].toRotationMatrix();
        }
        const auto n = static_cast<Eigen::Index>(3 * el.block_count());
        Eigen::Map<Eigen::VectorXd> f(force, n);
        f.setZero();
        Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 3 * k_max_blocks, 1> u(n);
        for (const Region& region : el.regions) {
            const Eigen::Matrix3d& r = m_r[e][region.pattern];
            for (std::size_t c = 0; c < 4; ++c) {
                u.segment<3>(static_cast<Eigen::Index>(3 * c)) = r.transpose() * (x[el.node[c]] - x[el.node[0]]) - (rest[el.node[c]] - rest[el.node[0]]);
                for (std::size_t j = 0; j < el.cuts.size(); ++j)
                    u.segment<3>(static_cast<Eigen::Index>(12 + 12 * j + 3 * c)) = r.transpose() * x[el.cuts[j].enriched[c]];
            }
            const Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 3 * k_max_blocks, 1> local = region.stiffness * u;
            for (Eigen::Index b = 0; b < n / 3; ++b) f.segment<3>(3 * b) += r * local.segment<3>(3 * b);
        }
    });
    parallel(m_model.block_count(), [&](std::size_t b) {
        Eigen::Vector3d sum = Eigen::Vector3d::Zero();
        for (std::uint32_t t = m_touch_start[b]; t < m_touch_start[b + 1]; ++t)
            sum += Eigen::Map<const Eigen::Vector3d>(&m_slots[m_slot_start[m_touch[t][0]] + 3 * m_touch[t][1]]);
        m_force.segment<3>(3 * static_cast<Eigen::Index>(b)) = sum;
        fill_row(b, scale_m, scale_k);
    });
}

void XfemOperator::block_rotations(std::vector<Eigen::Quaterniond>& out) const
{
    const auto& elements = m_model.elements();
    out.resize(m_model.block_count(), Eigen::Quaterniond::Identity());
    parallel(m_model.block_count(), [&](std::size_t b) {
        Eigen::Vector4d sum = Eigen::Vector4d::Zero();
        for (std::uint32_t t = m_touch_start[b]; t < m_touch_start[b + 1]; ++t) {
            const XfemElement& el = elements[m_touch[t][0]];
            const std::uint32_t corner = m_touch[t][1];
            // A node turns with its own region; a jump across cut j with the region across it.
            unsigned pattern = el.node_region(corner < 4 ? corner : (corner - 4) % 4);
            if (corner >= 4) pattern ^= 1u << ((corner - 4) / 4);
            fem::accumulate_rotation(sum, m_rotation[m_touch[t][0]][pattern]);
        }
        out[b] = sum.squaredNorm() > 0.0 ? Eigen::Quaterniond(sum.normalized()) : Eigen::Quaterniond::Identity();
    });
}

void XfemOperator::fill_row(std::size_t block, double scale_m, double scale_k)
{
    const auto& elements = m_model.elements();
    const int* outer = m_matrix.outerIndexPtr();
    double* row[3];
    for (std::size_t i = 0; i < 3; ++i) row[i] = m_matrix.valuePtr() + outer[3 * block + i];
    auto add = [&](std::uint32_t rank, const Eigen::Matrix3d& m) {
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) row[i][3 * rank + static_cast<std::uint32_t>(j)] += m(i, j);
    };
    const auto width = static_cast<std::size_t>(outer[3 * block + 1] - outer[3 * block]);
    for (std::size_t i = 0; i < 3; ++i) std::fill(row[i], row[i] + width, 0.0);
    std::uint32_t rank = 0;
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(m_block_mass, static_cast<Eigen::Index>(block)); it; ++it, ++rank)
        for (std::size_t i = 0; i < 3; ++i) row[i][3 * rank + i] = scale_m * it.value();
    for (std::uint32_t t = m_touch_start[block]; t < m_touch_start[block + 1]; ++t) {
        const std::size_t e = m_touch[t][0];
        const auto a = static_cast<Eigen::Index>(m_touch[t][1]);
        const XfemElement& el = elements[e];
        const std::uint32_t* ranks = &m_rank[m_rank_start[t]];
        if (!el.is_cut()) {
            const double lambda = scale_k * m_lame_volume[e][0], mu = scale_k * m_lame_volume[e][1];
            const Eigen::Matrix<double, 3, 4>& turned = m_turned_gradient[e];
            const Eigen::Vector3d ga = turned.col(a);
            for (Eigen::Index b = 0; b < 4; ++b) {
                const Eigen::Vector3d gb = turned.col(b);
                Eigen::Matrix3d m = lambda * ga * gb.transpose() + mu * gb * ga.transpose();
                m.diagonal().array() += mu * ga.dot(gb);
                if (const fem::VolumeHessian& v = m_volume_hessian[e]; v.active())
                    m += scale_k * v.block(el.geometry.gradient.row(a).transpose(), el.geometry.gradient.row(b).transpose());
                add(ranks[b], m);
            }
            continue;
        }
        for (const Region& region : el.regions) {
            const Eigen::Matrix3d& r = m_r[e][region.pattern];
            for (Eigen::Index b = 0; b < static_cast<Eigen::Index>(el.block_count()); ++b)
                add(ranks[b], scale_k * r * region.stiffness.block<3, 3>(3 * a, 3 * b) * r.transpose());
        }
    }
    // Held dofs: identity rows and columns.
    const int* inner = m_matrix.innerIndexPtr();
    for (std::size_t i = 0; i < 3; ++i) {
        const std::size_t dof = 3 * block + i;
        for (std::size_t k = 0; k < width; ++k) {
            const auto column = static_cast<std::size_t>(inner[static_cast<std::size_t>(outer[dof]) + k]);
            if (m_fixed[dof] || m_fixed[column]) row[i][k] = column == dof ? 1.0 : 0.0;
        }
    }
}

double XfemOperator::add_to_diagonal(const std::vector<std::uint32_t>& blocks, double relative)
{
    auto diagonal_entry = [&](std::size_t dof) -> double& {
        const std::size_t block = dof / 3;
        const int* first = m_block_mass.innerIndexPtr() + m_block_mass.outerIndexPtr()[block];
        const int* last = m_block_mass.innerIndexPtr() + m_block_mass.outerIndexPtr()[block + 1];
        const auto rank = static_cast<int>(std::lower_bound(first, last, static_cast<int>(block)) - first);
        return m_matrix.valuePtr()[m_matrix.outerIndexPtr()[dof] + 3 * rank + static_cast<int>(dof % 3)];
    };
    double sum = 0.0;
    std::size_t count = 0;
    for (std::size_t dof = 0; dof < 3 * m_model.node_count(); ++dof)
        if (!m_fixed[dof]) {
            sum += diagonal_entry(dof);
            ++count;
        }
    if (count == 0) return 0.0;
    const double shift = relative * sum / static_cast<double>(count);
    for (std::uint32_t b : blocks)
        for (std::size_t i = 0; i < 3; ++i)
            if (!m_fixed[3 * b + i]) diagonal_entry(3 * b + i) += shift;
    return shift;
}

void XfemOperator::add_point_stiffness(std::size_t e, const std::array<double, k_max_blocks>& w, const Eigen::Matrix3d& m)
{
    const XfemElement& el = m_model.elements()[e];
    for (std::size_t a = 0; a < el.block_count(); ++a) {
        if (w[a] == 0.0) continue;
        const std::uint32_t row = el.block(a);
        std::uint32_t t = m_touch_start[row];
        while (t < m_touch_start[row + 1] && !(m_touch[t][0] == e && m_touch[t][1] == a)) ++t;
        if (t == m_touch_start[row + 1]) throw std::logic_error("XfemOperator::add_point_stiffness: the element does not touch its block");
        for (std::size_t b = 0; b < el.block_count(); ++b) {
            const std::uint32_t rank = m_rank[m_rank_start[t] + b], column = el.block(b);
            for (std::size_t i = 0; i < 3; ++i)
                for (std::size_t j = 0; j < 3; ++j)
                    if (!m_fixed[3 * row + i] && !m_fixed[3 * column + j])
                        m_matrix.valuePtr()[m_matrix.outerIndexPtr()[3 * row + i] + 3 * rank + j] +=
                            w[a] * w[b] * m(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
        }
    }
}

void XfemOperator::multiply(const Eigen::VectorXd& p, Eigen::VectorXd& out) const
{
    out.resize(p.size());
    const int* outer = m_matrix.outerIndexPtr();
    const int* inner = m_matrix.innerIndexPtr();
    const double* values = m_matrix.valuePtr();
    tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, p.size(), 512), [&](const tbb::blocked_range<Eigen::Index>& r) {
        for (Eigen::Index i = r.begin(); i < r.end(); ++i) {
            double sum = 0.0;
            for (int k = outer[i]; k < outer[i + 1]; ++k) sum += values[k] * p[inner[k]];
            out[i] = sum;
        }
    });
}

void XfemOperator::mass_multiply(const Eigen::VectorXd& p, Eigen::VectorXd& out) const
{
    out.resize(p.size());
    parallel(m_model.block_count(), [&](std::size_t b) {
        Eigen::Vector3d sum = Eigen::Vector3d::Zero();
        for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(m_block_mass, static_cast<Eigen::Index>(b)); it; ++it)
            sum += it.value() * p.segment<3>(3 * it.col());
        out.segment<3>(3 * static_cast<Eigen::Index>(b)) = sum;
    });
}

} // namespace vox::isxfem
