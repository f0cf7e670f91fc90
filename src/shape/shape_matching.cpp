#include "shape/shape_matching.hpp"

#include "fem/corotation.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

namespace vox::shape {
namespace {

double ms_since(std::chrono::steady_clock::time_point t)
{
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

/// Sum over [0, n) of f(i), in parallel.
template <typename F>
double parallel_sum(std::size_t n, F&& f)
{
    return tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, n, 256), 0.0,
        [&](const tbb::blocked_range<std::size_t>& r, double s) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) s += f(i);
            return s;
        },
        [](double a, double b) { return a + b; });
}

} // namespace

ShapeMatching::ShapeMatching(const grid::BranchedGrid& grid, const fem::HexModel& model, const Settings& settings)
    : m_model(&model), m_settings(settings), m_clusters(grid, model, settings.coarse_levels)
{
    for (const ClusterLevel& level : m_clusters.levels()) {
        m_rotation.emplace_back(level.size(), Eigen::Quaterniond::Identity());
        m_goal.emplace_back(level.particle.size(), Eigen::Vector3d::Zero());
        m_energy.emplace_back(level.size(), 0.0);
        m_centroid.emplace_back(level.size(), Eigen::Vector3d::Zero());
        m_rest.push_back(level.rest);
        m_active.emplace_back(level.size(), 1);
        std::vector<std::uint32_t>& cluster = m_member_cluster.emplace_back(level.particle.size());
        for (std::uint32_t c = 0; c < level.size(); ++c) std::fill(cluster.begin() + level.start[c], cluster.begin() + level.start[c + 1], c);
    }
    m_skip.assign(m_clusters.levels().size(), 0);
    m_backoff.assign(m_clusters.levels().size(), k_origination_skip);
}

std::string ShapeMatching::description() const
{
    char line[160];
    std::snprintf(line, sizeof line, "%s hierarchical shape matching, %zu cluster levels (%zu clusters at the simulated level)",
                  m_settings.adaptive ? "adaptive" : "classic", m_clusters.levels().size(), m_clusters.levels().front().size());
    return line;
}

void ShapeMatching::goals(std::size_t level, std::size_t c, const std::vector<Eigen::Vector3d>& p, std::vector<Eigen::Vector3d>& out)
{
    const ClusterLevel& l = m_clusters.levels()[level];
    fit(level, p, {}, std::vector<unsigned char>(l.size(), 1));
    out.assign(m_goal[level].begin() + l.start[c], m_goal[level].begin() + l.start[c + 1]);
}

double ShapeMatching::energy(std::size_t level, const std::vector<Eigen::Vector3d>& p)
{
    return fit(level, p, {}, std::vector<unsigned char>(m_clusters.levels()[level].size(), 1));
}

void ShapeMatching::particle_goals(const std::vector<Eigen::Vector3d>& p, const std::vector<double>& scale,
                                   std::vector<Eigen::Vector3d>& goal, std::vector<double>& stiffness) const
{
    const ClusterLevel& l = m_clusters.levels().front();
    std::vector<Eigen::Vector3d> pull(p.size(), Eigen::Vector3d::Zero());
    stiffness.assign(p.size(), 0.0);
    // Serial: a snapshot's fit of every cluster takes about as long as one iteration's local step.
    for (std::size_t c = 0; c < l.size(); ++c) {
        const std::uint32_t begin = l.start[c], end = l.start[c + 1];
        const Eigen::Vector3d centroid = l.centroid(c, p);
        Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
        for (std::uint32_t m = begin; m < end; ++m) a += l.weight[m] * (p[l.particle[m]] - centroid) * m_rest[0][m].transpose();
        Eigen::Quaterniond q = m_rotation[0][c]; // warm start, left as the step has it
        fem::extract_rotation(a, q);
        const Eigen::Matrix3d r = q.toRotationMatrix();
        const double s = scale.empty() ? 1.0 : scale[c];
        for (std::uint32_t m = begin; m < end; ++m) {
            const double w = s * l.weight[m];
            pull[l.particle[m]] += w * (centroid + r * m_rest[0][m]);
            stiffness[l.particle[m]] += w;
        }
    }
    goal.resize(p.size());
    for (std::size_t j = 0; j < p.size(); ++j) goal[j] = stiffness[j] > 0.0 ? Eigen::Vector3d(pull[j] / stiffness[j]) : p[j];
}

double ShapeMatching::fit(std::size_t level, const std::vector<Eigen::Vector3d>& p, const std::vector<double>& scale,
                          const std::vector<unsigned char>& active)
{
    const ClusterLevel& l = m_clusters.levels()[level];
    std::vector<Eigen::Quaterniond>& rotation = m_rotation[level];
    std::vector<Eigen::Vector3d>& goal = m_goal[level];
    std::vector<double>& energy = m_energy[level];
    std::vector<Eigen::Vector3d>& centroids = m_centroid[level];
    return parallel_sum(l.size(), [&](std::size_t c) {
        if (!active[c]) return 0.0;
        const std::uint32_t begin = l.start[c], end = l.start[c + 1];
        const double s = scale.empty() ? 1.0 : scale[c];
        const Eigen::Vector3d centroid = centroids[c] = l.centroid(c, p);
        Eigen::Matrix3d a = Eigen::Matrix3d::Zero(); // the moment matrix sum w (p - c) q^T
        const std::vector<Eigen::Vector3d>& rest = m_rest[level];
        for (std::uint32_t m = begin; m < end; ++m) a += l.weight[m] * (p[l.particle[m]] - centroid) * rest[m].transpose();
        fem::extract_rotation(a, rotation[c]);
        const Eigen::Matrix3d r = rotation[c].toRotationMatrix();
        double e = 0.0;
        for (std::uint32_t m = begin; m < end; ++m) {
            goal[m] = centroid + r * rest[m];
            e += l.weight[m] * (p[l.particle[m]] - goal[m]).squaredNorm();
        }
        energy[c] = 0.5 * s * e;
        return energy[c];
    });
}

void ShapeMatching::plastic_rest(const fem::ImplicitSolver& solver)
{
    const ClusterLevel& l = m_clusters.levels().front();
    const Eigen::Matrix3d& frame = m_model->frame();
    for (std::size_t e = 0; e < l.size(); ++e) {
        const Eigen::Matrix3d strain = frame * solver.plastic_strain(static_cast<std::uint32_t>(e)) * frame.transpose();
        for (std::uint32_t m = l.start[e]; m < l.start[e + 1]; ++m) m_rest[0][m] = l.rest[m] + strain * l.rest[m];
    }
}

void ShapeMatching::creep(fem::ImplicitSolver& solver, const std::vector<Eigen::Vector3d>& p, double dt)
{
    // As the FEM's plasticity (fem/implicit_solver.hpp, MaterialBehaviour): the cluster's strain
    // against its original rest shape, from its best linear fit F = A_pq A_qq^-1 unrotated by
    // F's own rotation, index-aligned frame; the plastic strain creeps toward its elastic excess.
    const ClusterLevel& l = m_clusters.levels().front();
    const Eigen::Matrix3d& frame = m_model->frame();
    const std::vector<fem::MaterialBehaviour>& behaviour = solver.behaviour();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, l.size(), 64), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t e = range.begin(); e != range.end(); ++e) {
            const auto material = static_cast<std::size_t>(m_model->elements()[e].material);
            if (material >= behaviour.size() || !behaviour[material].plastic()) continue;
            const fem::MaterialBehaviour& b = behaviour[material];
            Eigen::Matrix3d apq = Eigen::Matrix3d::Zero(), aqq = Eigen::Matrix3d::Zero();
            for (std::uint32_t m = l.start[e]; m < l.start[e + 1]; ++m) {
                apq += l.weight[m] * (p[l.particle[m]] - m_centroid[0][e]) * l.rest[m].transpose();
                aqq += l.weight[m] * l.rest[m] * l.rest[m].transpose();
            }
            const Eigen::Matrix3d f = apq * aqq.inverse();
            Eigen::Quaterniond q = m_rotation[0][e];
            fem::extract_rotation(f, q);
            const Eigen::Matrix3d g = q.toRotationMatrix().transpose() * f;
            const Eigen::Matrix3d strain = frame.transpose() * (0.5 * (g + g.transpose()) - Eigen::Matrix3d::Identity()) * frame;
            Eigen::Matrix3d plastic = solver.plastic_strain(static_cast<std::uint32_t>(e));
            const double yield = b.yield_strain * (1.0 - (1.0 - b.wet_yield_ratio) * solver.water(static_cast<std::uint32_t>(e)));
            const Eigen::Matrix3d elastic = strain - plastic;
            if (elastic.norm() > yield) plastic += std::min(1.0, dt * b.creep_per_s) * elastic;
            if (const double norm = plastic.norm(); norm > b.max_strain) plastic *= b.max_strain / norm;
            solver.set_plastic_strain(static_cast<std::uint32_t>(e), plastic);
        }
    });
}

fem::StepStats ShapeMatching::step(fem::ImplicitSolver& solver)
{
    const auto start = std::chrono::steady_clock::now();
    fem::StepStats stats;
    const fem::SolverOptions& options = solver.options();
    const bool quasi_static = options.quasi_static;
    const double dt = options.dt_s;
    const std::vector<double>& mass = m_model->nodal_mass();
    const std::vector<unsigned char>& fixed = solver.fixed_dofs();
    std::vector<Eigen::Vector3d>& x = solver.positions();
    std::vector<Eigen::Vector3d>& v = solver.velocities();
    const std::size_t n = x.size();
    const std::size_t levels = m_clusters.levels().size();

    // The particles' own terms: inertia toward y = x + dt v + dt^2 f / m, where each particle
    // goes under its velocity and the constant loads f alone (the paper's "virtually displaced
    // via Newton's second law"), and the contacts at their stiffness. The iterations start there,
    // so that a step cut short leaves the loads' motion in (softer) rather than out (a free fall
    // slowed by the object's stiffness).
    // Statically, no inertia: the loads f stay as forces and the iterations start at x.
    // Rayleigh's mass damping alpha as the FEM's implicit Euler takes it: (1 + alpha dt) M v' =
    // M v + dt f, so the inertia weighs (1 + alpha dt) m / dt^2 and y = x + dt (v + dt f / m) / (1 + alpha dt).
    const double damped = quasi_static ? 1.0 : 1.0 + dt * options.rayleigh_mass_per_s;
    std::vector<double> inertia(n, 0.0);
    std::vector<Eigen::Vector3d> y(n), f(n), p(n);
    for (std::size_t j = 0; j < n; ++j) {
        f[j] = mass[j] * solver.gravity() + solver.external_forces()[j];
        y[j] = x[j];
        if (!quasi_static && mass[j] > 0.0) {
            inertia[j] = damped * mass[j] / (dt * dt);
            y[j] += dt * (v[j] + dt * f[j] / mass[j]) / damped;
            f[j].setZero();
        }
        p[j] = quasi_static ? x[j] : y[j];
        for (int a = 0; a < 3; ++a)
            if (fixed[3 * j + static_cast<std::size_t>(a)]) p[j][a] = x[j][a];
    }
    if (solver.has_plasticity()) plastic_rest(solver);
    std::vector<Eigen::Matrix3d> contact_stiffness = solver.contact_node_stiffness();
    const bool has_contact = !solver.contact().empty() || !solver.pair_contacts().empty();
    Eigen::VectorXd contact_force = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(3 * n));
    // Water softens the simulated level's clusters as it softens the FEM's elements.
    std::vector<double> scale(m_clusters.levels().front().size(), 1.0);
    for (std::size_t e = 0; e < scale.size(); ++e)
        scale[e] = solver.stiffness_scale(static_cast<std::uint32_t>(e), m_model->elements()[e].material);

    // Phi's particle terms (inertia and loads, relative to y) and their non-negative part.
    auto particle_terms = [&](double& positive) {
        positive = parallel_sum(n, [&](std::size_t j) { return 0.5 * inertia[j] * (p[j] - y[j]).squaredNorm(); });
        return positive - parallel_sum(n, [&](std::size_t j) { return f[j].dot(p[j] - y[j]); });
    };

    // One Jacobi pass of `level`: each particle to the minimiser of its terms with the goals fixed.
    auto move = [&](std::size_t level, const std::vector<double>& level_scale) {
        const ClusterLevel& l = m_clusters.levels()[level];
        const std::vector<Eigen::Vector3d>& goal = m_goal[level];
        const std::vector<unsigned char>& active = m_active[level];
        if (has_contact) {
            contact_force.setZero();
            solver.add_contact_forces(p, contact_force);
        }
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 256), [&](const tbb::blocked_range<std::size_t>& range) {
            for (std::size_t j = range.begin(); j != range.end(); ++j) {
                Eigen::Vector3d pull = Eigen::Vector3d::Zero();
                double weight = 0.0;
                for (std::uint32_t k = l.particle_start[j]; k < l.particle_start[j + 1]; ++k) {
                    const std::uint32_t m = l.particle_member[k];
                    const std::uint32_t c = m_member_cluster[level][m];
                    if (!active[c]) continue;
                    const double w = l.weight[m] * (level_scale.empty() ? 1.0 : level_scale[c]);
                    pull += w * goal[m];
                    weight += w;
                }
                if (weight == 0.0) continue;
                Eigen::Vector3d r = inertia[j] * (y[j] - p[j]) + f[j] + pull - weight * p[j];
                Eigen::Matrix3d d = (inertia[j] + weight) * Eigen::Matrix3d::Identity();
                if (has_contact) {
                    r += contact_force.segment<3>(static_cast<Eigen::Index>(3 * j));
                    d += contact_stiffness[j];
                }
                for (int a = 0; a < 3; ++a)
                    if (fixed[3 * j + static_cast<std::size_t>(a)]) {
                        r[a] = 0.0;
                        d.row(a).setZero();
                        d.col(a).setZero();
                        d(a, a) = 1.0;
                    }
                p[j] += d.ldlt().solve(r);
            }
        });
    };

    // Rayleigh's stiffness damping beta with the global step: the clusters' matrix L stands for
    // the stiffness, adding beta / (2 dt) (p - x)^T L (p - x) to Phi, so the matrix is
    // M' / dt^2 + (1 + beta / dt) L and the right-hand side gains (beta / dt) L x.
    const double beta = quasi_static || !m_settings.global_step ? 0.0 : options.rayleigh_stiffness_s / dt;
    std::vector<double> damped_scale = scale;
    for (double& s : damped_scale) s *= 1.0 + beta;
    std::vector<Eigen::Vector3d> damping_pull(n, Eigen::Vector3d::Zero()); // (beta / dt) L x
    // (beta / dt) L u from the factored matrix A' = diag(inertia) + (1 + beta / dt) L.
    auto damping_times = [&](const std::vector<Eigen::Vector3d>& u, std::vector<Eigen::Vector3d>& out) {
        m_global.multiply_full(u, out);
        for (std::size_t j = 0; j < n; ++j) out[j] = beta / (1.0 + beta) * (out[j] - inertia[j] * u[j]);
    };
    if (m_settings.global_step) {
        m_global.prepare(m_clusters.levels().front(), damped_scale, inertia, fixed);
        if (beta > 0.0) damping_times(x, damping_pull);
    }
    // The global step on the simulated level: the minimiser of Phi with every rotation fixed, as
    // a correction of p solved with the factored matrix; contacts (a few nodes, changing every
    // frame) by conjugate gradients preconditioned with it.
    auto global_move = [&] {
        const ClusterLevel& l = m_clusters.levels().front();
        const std::vector<Eigen::Vector3d>& goal = m_goal.front();
        const std::vector<Eigen::Vector3d>& centroid = m_centroid.front();
        const std::vector<std::uint32_t>& cluster = m_member_cluster.front();
        std::vector<Eigen::Vector3d> ap, r(n), z, d, q, delta(n, Eigen::Vector3d::Zero());
        m_global.multiply_full(p, ap);
        auto contact_at = [&](const std::vector<Eigen::Vector3d>& at) {
            Eigen::VectorXd f_c = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(3 * n));
            solver.add_contact_forces(at, f_c);
            return f_c;
        };
        const Eigen::VectorXd f0 = has_contact ? contact_at(p) : Eigen::VectorXd();
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 256), [&](const tbb::blocked_range<std::size_t>& range) {
            for (std::size_t j = range.begin(); j != range.end(); ++j) {
                Eigen::Vector3d turned = Eigen::Vector3d::Zero(); // sum of w R q
                for (std::uint32_t k = l.particle_start[j]; k < l.particle_start[j + 1]; ++k) {
                    const std::uint32_t m = l.particle_member[k];
                    turned += scale[cluster[m]] * l.weight[m] * (goal[m] - centroid[cluster[m]]);
                }
                r[j] = inertia[j] * y[j] + f[j] + turned + damping_pull[j] - ap[j];
                if (has_contact) r[j] += f0.segment<3>(static_cast<Eigen::Index>(3 * j));
                for (int a = 0; a < 3; ++a)
                    if (fixed[3 * j + static_cast<std::size_t>(a)]) r[j][a] = 0.0;
            }
        });
        m_global.solve(r, z);
        if (!has_contact) {
            for (std::size_t j = 0; j < n; ++j) p[j] += z[j];
            return;
        }
        auto dot = [&](const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b) {
            double sum = 0.0;
            for (std::size_t j = 0; j < n; ++j) sum += a[j].dot(b[j]);
            return sum;
        };
        // (A + K) u = A u + F(p) - F(p + u) on the free dofs (the contacts' forces are linear).
        auto apply = [&](const std::vector<Eigen::Vector3d>& u, std::vector<Eigen::Vector3d>& out) {
            m_global.multiply(u, out);
            std::vector<Eigen::Vector3d> moved(n);
            for (std::size_t j = 0; j < n; ++j) moved[j] = p[j] + u[j];
            const Eigen::VectorXd f1 = contact_at(moved);
            for (std::size_t j = 0; j < n; ++j)
                for (int a = 0; a < 3; ++a)
                    if (!fixed[3 * j + static_cast<std::size_t>(a)])
                        out[j][a] += f0[static_cast<Eigen::Index>(3 * j + a)] - f1[static_cast<Eigen::Index>(3 * j + a)];
        };
        d = z;
        double rz = dot(r, z);
        const double r0 = std::sqrt(dot(r, r));
        for (int it = 0; it < k_contact_iterations && rz > 0.0; ++it) {
            apply(d, q);
            const double alpha = rz / dot(d, q);
            for (std::size_t j = 0; j < n; ++j) {
                delta[j] += alpha * d[j];
                r[j] -= alpha * q[j];
            }
            if (std::sqrt(dot(r, r)) <= k_contact_tolerance * r0) break;
            m_global.solve(r, z);
            const double rz_next = dot(r, z);
            for (std::size_t j = 0; j < n; ++j) d[j] = z[j] + (rz_next / rz) * d[j];
            rz = rz_next;
        }
        for (std::size_t j = 0; j < n; ++j) p[j] += delta[j];
    };

    // Which levels this step starts from (origination) and how many iterations each may take.
    std::size_t top = levels - 1;
    if (m_settings.adaptive)
        while (top > 0 && m_skip[top] > 0) --top;
    for (std::size_t l = 0; l < levels; ++l)
        if (m_skip[l] > 0) --m_skip[l];
    m_report = StepReport{};
    m_report.iterations.assign(levels, 0);
    m_report.active.assign(levels, 0);
    int budget = m_settings.max_iterations;
    const double tiny = 1e-300;
    // Phi is always measured on the simulated level's clusters: coarser levels only propose moves,
    // kept when they lower it (a coarse cluster is stiffer than the fine ones it spans, and
    // converging it alone would pull the object toward its own, coarser minimum).
    const std::vector<unsigned char> every(m_clusters.levels().front().size(), 1);
    auto measure = [&](const std::vector<unsigned char>& fitted, double& size) {
        fit(0, p, scale, fitted);
        double positive = 0.0;
        double terms = particle_terms(positive) + (has_contact ? solver.contact_potential(p) : 0.0);
        if (beta > 0.0) {
            std::vector<Eigen::Vector3d> moved(n), pulled;
            for (std::size_t j = 0; j < n; ++j) moved[j] = p[j] - x[j];
            damping_times(moved, pulled);
            double damping = 0.0;
            for (std::size_t j = 0; j < n; ++j) damping += 0.5 * moved[j].dot(pulled[j]);
            terms += damping;
            positive += damping;
        }
        double elastic = 0.0;
        for (double e : m_energy[0]) elastic += e; // clusters not fitted count with their last energy
        size = positive + elastic;
        return terms + elastic;
    };
    double size = 0.0;
    double phi = measure(every, size);
    m_report.initial_potential_j = phi;
    std::vector<Eigen::Vector3d> before;
    // Cycles through the levels, coarse to fine (the paper's sweep, repeated as a multigrid's
    // V-cycles: a level's iterations per cycle are capped so that the coarse levels carry on what
    // the fine ones leave), until a cycle lowers Phi by less than the termination rate or the budget
    // is spent.
    // Pair contacts (obstacles, pieces) only push: after the iterations those that would pull let
    // go and the waiting ones pressed in join, and the step goes on from there while that
    // changes something (the FEM's release passes, fem/pair_contact.hpp).
    for (int pass = 0;; ++pass) {
        bool subdivide = false; // the first cycle starts before any load has deformed anything
        for (int cycle = 0; budget > 0; ++cycle) {
            const double phi_cycle = phi;
            for (std::size_t level = top + 1; level-- > 0;) {
                const ClusterLevel& l = m_clusters.levels()[level];
                const std::vector<double>& level_scale = level == 0 ? scale : std::vector<double>{};
                // Subdivision: below the top, the children of the clusters still deformed; not in the
                // first cycle, whose start has seen no load yet (a tool pressing an object at rest),
                // nor in a cycle after one that stalled.
                std::vector<unsigned char>& active = m_active[level];
                const double threshold = m_settings.subdivision_strain * m_settings.subdivision_strain;
                std::size_t count = 0;
                for (std::size_t c = 0; c < l.size(); ++c) {
                    bool on = true;
                    if (subdivide && level < top) {
                        const std::uint32_t parent = l.parent[c];
                        const ClusterLevel& above = m_clusters.levels()[level + 1];
                        on = m_active[level + 1][parent] &&
                             2.0 * m_energy[level + 1][parent] > threshold * above.rest_moment[parent];
                    }
                    active[c] = on ? 1 : 0;
                    count += on ? 1 : 0;
                }
                m_report.active[level] = count;
                if (level > 0 && m_settings.global_step) {
                    // The global step carries loads across the object in one iteration, so a coarse
                    // level proposes no moves: it is fitted for the subdivision of the next finer one.
                    fit(level, p, level_scale, active);
                    continue;
                }
                // Each finer level keeps at least one iteration of the budget.
                const int cap = std::max(1, std::min(k_cycle_iterations, budget - static_cast<int>(level)));
                int it = 0;
                bool terminated = count == 0;
                while (it < cap && count > 0) {
                    if (level > 0) { // the simulated level's goals are those of the last measure
                        fit(level, p, level_scale, active);
                        before = p;
                    }
                    if (level == 0 && m_settings.global_step)
                        global_move();
                    else
                        move(level, level_scale);
                    ++it;
                    double size_now = 0.0;
                    double phi_now = measure(level == 0 ? active : every, size_now);
                    if (level > 0 && phi_now > phi) {
                        // A coarse move overshoots where its clusters pull particles the fine ones hold:
                        // shorter steps along it, the first that lowers Phi kept, else none.
                        const std::vector<Eigen::Vector3d> full = p;
                        for (double step = 0.5; step > 0.06 && phi_now > phi; step *= 0.5) {
                            for (std::size_t j = 0; j < n; ++j) p[j] = before[j] + step * (full[j] - before[j]);
                            phi_now = measure(every, size_now);
                        }
                        if (phi_now > phi) {
                            p = before;
                            phi_now = measure(every, size_now);
                        }
                    }
                    const double rate = (phi - phi_now) / std::max({size, size_now, tiny});
                    phi = phi_now;
                    size = size_now;
                    if (cycle == 0 && it == 1 && level > 0 && m_settings.adaptive) {
                        if (rate < m_settings.termination_rate) { // skipped for a while, longer each time in a row
                            m_skip[level] = m_backoff[level];
                            m_backoff[level] = std::min(2 * m_backoff[level], k_origination_skip_max);
                        } else {
                            m_backoff[level] = k_origination_skip;
                        }
                    }
                    if (rate < m_settings.termination_rate) {
                        terminated = true;
                        break;
                    }
                }
                (void)terminated;
                m_report.iterations[level] += it;
                m_report.total_iterations += it;
                budget -= it;
            }
            if (phi_cycle - phi < m_settings.termination_rate * std::max(size, tiny)) {
                // A cycle that left clusters out may have stalled on them: done only once a cycle of
                // every cluster stalls too (a bar springing back statically left 4.5 % of its bend).
                if (!subdivide) {
                    m_report.converged = true;
                    break;
                }
                subdivide = false;
            } else {
                subdivide = m_settings.adaptive;
            }
        }
        if (pass + 1 >= fem::k_release_passes || solver.pair_contacts().empty() || solver.settle_pairs(p) == 0) break;
        contact_stiffness = solver.contact_node_stiffness();
        budget = std::max(budget, m_settings.max_iterations / 4);
        phi = measure(every, size);
    }
    // The simulated level's energy at the end, every cluster fitted.
    std::copy(every.begin(), every.end(), m_active[0].begin());
    m_report.potential_j = measure(every, size);
    double elastic = 0.0;
    for (double e : m_energy[0]) elastic += e;
    m_report.elastic_energy_j = elastic;

    if (solver.has_plasticity()) creep(solver, p, dt);

    double kinetic = 0.0;
    for (std::size_t j = 0; j < n; ++j) {
        if (quasi_static) {
            v[j].setZero();
        } else {
            v[j] = (p[j] - x[j]) / dt;
            for (int a = 0; a < 3; ++a)
                if (fixed[3 * j + static_cast<std::size_t>(a)]) v[j][a] = 0.0;
            kinetic += 0.5 * mass[j] * v[j].squaredNorm();
        }
        x[j] = p[j];
    }
    stats.cg_iterations = m_report.total_iterations; // the step's iterations, as the FEM reports its CG's
    stats.kinetic_energy_j = kinetic;
    stats.elastic_energy_j = elastic;
    stats.converged = m_report.converged;
    stats.solve_ms = ms_since(start);
    return stats;
}

} // namespace vox::shape
