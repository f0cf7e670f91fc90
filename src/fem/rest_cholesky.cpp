#include "fem/rest_cholesky.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <utility>

#ifdef __linux__
#include <sched.h>
#include <sys/resource.h>
#include <unistd.h>
#endif

namespace vox::fem {
namespace {

/// Lowers the calling thread's priority, so that a background factorisation takes the CPU the
/// frame's threads (and, in the viewer, the haptic loop on the other core) leave rather than
/// competing with them. On the Is-XFEM bench, 2 threads, the frames' p95 was 66-74 ms at normal
/// priority and 53-65 ms at nice 10 (104-114 ms factoring in the frame). Nice 10 (weight 110
/// against 1,024) rather than 19: when a frame waits for the factor, other processes should not
/// starve it.
void lower_priority()
{
#ifdef __linux__
    setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), 10); // Linux: a per-thread nice; best effort
#endif
}

/// Cores the process may run on (taskset, cgroups).
int usable_cores()
{
#ifdef __linux__
    cpu_set_t set;
    if (sched_getaffinity(0, sizeof set, &set) == 0) return CPU_COUNT(&set);
#endif
    return 2;
}

const SystemMatrix& assembled(const SystemMatrix* a)
{
    if (!a) throw std::logic_error("RestCholesky::update: a new factor or correction needs the assembled matrix");
    return *a;
}

} // namespace

RestCholesky::RestCholesky(const Eigen::Matrix3d& frame, int refactor_iterations, double background_flops)
    : m_frame(frame), m_refactor_iterations(refactor_iterations), m_background_flops(background_flops)
{
}

double RestCholesky::background_flops_here() { return usable_cores() > 1 ? k_background_flops : INFINITY; }

RestCholesky::~RestCholesky()
{
    if (m_running.valid()) m_running.wait(); // its thread writes m_next
}

void RestCholesky::Factorization::take(const SystemMatrix& a, std::vector<unsigned char> held, std::vector<Eigen::Quaterniond> at,
                                       std::vector<std::uint32_t> contacts, std::size_t solve_threads)
{
    const bool new_pattern = !taken || held != fixed || a.rows() != rows || a.nonZeros() != nonzeros;
    const Eigen::SparseMatrix<double> column_major(a);
    // A singular K (nothing holds the object) may still factor, with pivots at round-off level:
    // that is a failure too.
    ok = factor.factor(column_major, new_pattern, solve_threads);
    matrix = a;
    rows = a.rows();
    nonzeros = a.nonZeros();
    fixed = std::move(held);
    rotation = std::move(at);
    contact_blocks = std::move(contacts);
    taken = true;
}

bool RestCholesky::same_holds(const std::vector<unsigned char>& held, const std::vector<unsigned char>& fixed)
{
    return fixed.size() >= held.size() && std::equal(held.begin(), held.end(), fixed.begin()) &&
           std::all_of(fixed.begin() + static_cast<std::ptrdiff_t>(held.size()), fixed.end(), [](unsigned char f) { return f == 0; });
}

bool RestCholesky::must_refactor(const std::vector<unsigned char>& fixed, std::size_t blocks) const
{
    const bool usable = m_current->taken && !m_failed && m_current->factor.factor_flops() >= m_background_flops;
    // Grown without blocks_changed(): nothing says what changed.
    const bool unexplained = blocks > m_covered_blocks && !m_correction_dirty;
    return (m_stale && !usable) || m_invalid || !same_holds(m_current->fixed, fixed) ||
           blocks < m_current->rotation.size() || unexplained;
}

void RestCholesky::start_stretch(std::vector<unsigned char> changed, bool dirty)
{
    m_failed = !m_current->ok;
    m_stale = m_invalid = false;
    m_changed = std::move(changed);
    m_correction_dirty = dirty;
    m_covered_blocks = m_current->rotation.size();
    m_correction.clear();
    m_patch.clear();
    // A CG iteration streams the factor twice (2 flops an entry each way) and multiplies by
    // the matrix once (2 flops a non-zero). The factorisation's flops run in small dense
    // blocks at about half the solve's rate per flop (measured on the liver at level 4: 380
    // Mflop in 57 ms against 5.8 Mflop in 0.45 ms), hence the factor 2.
    m_iteration_flops = 4.0 * static_cast<double>(m_current->factor.entries()) + 2.0 * static_cast<double>(m_current->nonzeros);
    m_refactor_cost = 2.0 * m_current->factor.factor_flops() / m_iteration_flops;
    // One taken in the frame also stalls that frame: the user feels it, so it is bought half as
    // often (ski rental at twice the price, still within three times the best total).
    if (m_current->factor.factor_flops() >= k_background_flops && !std::isfinite(m_background_flops)) m_refactor_cost *= 2.0;
    m_baseline = -1;
    m_excess = 0.0;
}

void RestCholesky::join()
{
    if (m_running.wait_for(std::chrono::seconds(0)) != std::future_status::ready) ++m_frames_waited;
    ++m_factorizations;
    ++m_background_factorizations;
    m_running.get();
}

void RestCholesky::refactor(const SystemMatrix& a, const std::vector<unsigned char>& fixed, const std::vector<Eigen::Quaterniond>& node_rotation)
{
    if (m_running.valid()) join(); // and discard: this factor is newer
    m_current->take(a, fixed, node_rotation, m_contact_blocks, SupernodalFactor::solve_threads());
    ++m_factorizations;
    start_stretch(std::vector<unsigned char>(node_rotation.size(), 0), false);
}

void RestCholesky::launch(const SystemMatrix& a, const std::vector<unsigned char>& fixed, const std::vector<Eigen::Quaterniond>& node_rotation)
{
    // The thread gets copies and m_next; the solves will run on this thread, so the factor is
    // scheduled for its threads.
    m_running = std::async(std::launch::async, [next = m_next.get(), matrix = a, fixed, node_rotation, contacts = m_contact_blocks,
                                                threads = SupernodalFactor::solve_threads()]() mutable {
        lower_priority();
        next->take(matrix, std::move(fixed), std::move(node_rotation), std::move(contacts), threads);
    });
    m_running_cost = m_refactor_cost;
    m_running_iterations = 0;
    m_changed_since_launch.assign(node_rotation.size(), 0);
    m_dirty_since_launch = false;
    m_stale = false;
}

void RestCholesky::swap_in(const std::vector<unsigned char>& fixed, std::size_t blocks)
{
    join();
    if (!same_holds(m_next->fixed, fixed) || blocks < m_next->rotation.size()) { // discarded: due again, now
        m_stale = true;
        return;
    }
    std::swap(m_current, m_next);
    start_stretch(std::exchange(m_changed_since_launch, {}), m_dirty_since_launch);
}

bool RestCholesky::recorrect(const SystemMatrix& a, const std::vector<unsigned char>& fixed, std::size_t blocks)
{
    // The rows changed since the factor's snapshot: cut, added, and those whose contact terms moved
    // (the snapshot's contacts and this step's: the tool presses where it cuts).
    std::vector<std::uint32_t> seeds;
    for (std::uint32_t b = 0; b < blocks; ++b)
        if (b >= m_changed.size() || m_changed[b]) seeds.push_back(b);
    const std::size_t cut_seeds = seeds.size();
    seeds.insert(seeds.end(), m_current->contact_blocks.begin(), m_current->contact_blocks.end());
    seeds.insert(seeds.end(), m_contact_blocks.begin(), m_contact_blocks.end());
    m_correction_dirty = false;
    m_covered_blocks = blocks;
    m_patch.clear();
    // Exact while that costs at most a factorisation (or about a millisecond) and covers at most
    // an eighth of the system.
    double flops = 0.0;
    const auto max_dofs = static_cast<std::size_t>(a.rows() / 8);
    const double max_flops = std::max(m_current->factor.factor_flops(), 1e7);
    const bool built = m_exact_cuts && m_correction.build(m_current->factor, m_current->matrix, a, seeds, m_warp, fixed, max_dofs, max_flops, flops);
    m_excess += flops / m_iteration_flops; // the rent-or-buy rule counts it as iterations
    if (built) return true;
    // Past that (a cut through many elements at once) a new factor is the better buy; until it
    // comes, an exact solve on the patch of the changed blocks with one ring is added to the
    // factor (additive Schwarz: sound, not exact).
    if (m_exact_cuts && !m_running.valid()) m_stale = true; // else one is on its way
    seeds.resize(cut_seeds); // the patch holds the cut's blocks and their ring
    return m_patch.build(a, seeds, a.rows() / 8);
}

void RestCholesky::blocks_changed(const std::vector<std::uint32_t>& blocks)
{
    for (std::uint32_t b : blocks)
        if (b < m_changed.size()) m_changed[b] = 1;
    m_correction_dirty = true;
    if (!m_running.valid()) return;
    // The background factor's snapshot predates this too: its correction must cover it.
    for (std::uint32_t b : blocks)
        if (b < m_changed_since_launch.size()) m_changed_since_launch[b] = 1;
    m_dirty_since_launch = true;
}

void RestCholesky::update(const SystemMatrix* a, const std::vector<unsigned char>& fixed,
                          const std::vector<Eigen::Quaterniond>& node_rotation)
{
    if (m_running.valid() && m_running_iterations >= m_running_cost && !m_invalid) swap_in(fixed, node_rotation.size());
    if (must_refactor(fixed, node_rotation.size())) {
        refactor(assembled(a), fixed, node_rotation);
    } else {
        // Grown or changed since the factor's snapshot: correct it (in the frame the nodes are
        // turned to now), or factor anew when that fails. The current factor, corrected,
        // preconditions until a new one launched here swaps in.
        set_warps(node_rotation);
        if (m_correction_dirty && !recorrect(assembled(a), fixed, node_rotation.size()))
            refactor(*a, fixed, node_rotation);
        else if (m_stale)
            launch(assembled(a), fixed, node_rotation);
    }
    set_warps(node_rotation);
}

void RestCholesky::set_warps(const std::vector<Eigen::Quaterniond>& node_rotation)
{
    // World-frame rotation of each factored block since the factorisation: F Q_now Q_factored^-1 F^T.
    const std::vector<Eigen::Quaterniond>& factored = m_current->rotation;
    const std::size_t blocks = factored.size();
    m_warp.resize(blocks);
    for (std::size_t n = 0; n < blocks; ++n)
        m_warp[n] = m_frame * (node_rotation[n] * factored[n].conjugate()).toRotationMatrix() * m_frame.transpose();
    // The jumps the factor holds (newer ones are left to the correction or the patch).
    m_jump_warp.clear();
    for (const JumpBlock& jump : m_jumps)
        if (jump.block < blocks && jump.node < blocks) m_jump_warp.push_back({jump, jump.sign * (m_warp[jump.block] - m_warp[jump.node])});
}

void RestCholesky::report_iterations(int iterations)
{
    if (m_running.valid()) { // a new factor is on its way: the iterations only count towards its swap
        m_running_iterations += iterations;
        return;
    }
    if (m_baseline < 0 || iterations < m_baseline) m_baseline = iterations;
    // A patch solve streams its double-precision factor twice per iteration: 8 flop-equivalents
    // an entry against the float factor's 4.
    const double extra = (m_correction.apply_flops() + 8.0 * static_cast<double>(m_patch.entries())) / m_iteration_flops;
    m_excess += iterations * (1.0 + extra) - m_baseline;
    m_stale = m_stale || iterations > m_refactor_iterations || m_excess >= m_refactor_cost;
}

void RestCholesky::apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const
{
    // z = W A_0^-1 W^T r, W the warp with its jump couplings, on the factored dofs, A_0 corrected
    // for the rows changed since it was factored.
    const Eigen::Index rows = m_current->rows;
    const std::vector<unsigned char>& fixed = m_current->fixed;
    m_scratch.resize(rows);
    for (std::size_t n = 0; n < m_warp.size(); ++n) {
        const auto i = static_cast<Eigen::Index>(3 * n);
        m_scratch.segment<3>(i) = m_warp[n].transpose() * r.segment<3>(i);
    }
    for (const auto& [jump, j] : m_jump_warp)
        m_scratch.segment<3>(3 * static_cast<Eigen::Index>(jump.node)) += j.transpose() * r.segment<3>(3 * static_cast<Eigen::Index>(jump.block));
    for (Eigen::Index i = 0; i < rows; ++i)
        if (fixed[static_cast<std::size_t>(i)]) m_scratch[i] = 0.0;
    if (m_correction.empty()) m_current->factor.solve(m_scratch);
    else m_current->factor.solve(m_scratch, [&](std::span<float> y) { m_correction.correct(y, r, m_new_z); });
    z.setZero(r.size());
    for (std::size_t n = 0; n < m_warp.size(); ++n) {
        const auto i = static_cast<Eigen::Index>(3 * n);
        z.segment<3>(i) = m_warp[n] * m_scratch.segment<3>(i);
    }
    for (const auto& [jump, j] : m_jump_warp)
        z.segment<3>(3 * static_cast<Eigen::Index>(jump.block)) += j * m_scratch.segment<3>(3 * static_cast<Eigen::Index>(jump.node));
    if (!m_correction.empty()) m_correction.add_new(m_new_z, z);
    if (!m_patch.empty()) m_patch.add_to(r, z);
    for (std::size_t i = 0; i < fixed.size(); ++i)
        if (fixed[i]) z[static_cast<Eigen::Index>(i)] = 0.0;
}

} // namespace vox::fem
