#include "shape/cluster_hierarchy.hpp"

#include <algorithm>
#include <stdexcept>

namespace vox::shape {
namespace {

/// Corners below this share of an element's mass (times 8) still weigh this much: a nearly empty
/// corner would otherwise belong to no cluster at all (the FEM's stiffness floor, fem/hex_model.hpp).
constexpr double k_weight_floor = 1e-3;

/// Fills the cluster's rest offsets from its weighted rest centroid and its rest moment.
void finish_cluster(ClusterLevel& level, std::size_t c, const std::vector<Eigen::Vector3d>& rest)
{
    const std::uint32_t begin = level.start[c], end = level.start[c + 1];
    const Eigen::Vector3d centroid = level.centroid(c, rest);
    double moment = 0.0;
    for (std::uint32_t m = begin; m < end; ++m) {
        level.rest[m] = rest[level.particle[m]] - centroid;
        moment += level.weight[m] * level.rest[m].squaredNorm();
    }
    level.rest_moment.push_back(moment);
}

/// Groups the members by particle (ClusterLevel::particle_start and particle_member).
void index_particles(ClusterLevel& level, std::size_t particles)
{
    level.particle_start.assign(particles + 1, 0);
    for (std::uint32_t p : level.particle) ++level.particle_start[p + 1];
    for (std::size_t p = 0; p < particles; ++p) level.particle_start[p + 1] += level.particle_start[p];
    level.particle_member.resize(level.particle.size());
    std::vector<std::uint32_t> next(level.particle_start.begin(), level.particle_start.end() - 1);
    for (std::uint32_t m = 0; m < level.particle.size(); ++m) level.particle_member[next[level.particle[m]]++] = m;
}

} // namespace

double ClusterHierarchy::element_mu(const fem::HexElement& element, double d, double ratio)
{
    double trace = 0.0;
    for (int i = 0; i < 24; ++i) trace += (*element.stiffness)(i, i);
    return 3.0 * trace / (8.0 * d * (ratio + 4.0));
}

ClusterHierarchy::ClusterHierarchy(const grid::BranchedGrid& grid, const fem::HexModel& model, int coarse_levels)
{
    if (coarse_levels < 0) throw std::invalid_argument("ClusterHierarchy: negative number of coarse levels");
    const auto& elements = model.elements();
    const auto& rest = model.rest_positions();
    m_particles = model.node_count();

    // The model's own level: one cluster per element.
    ClusterLevel fine;
    fine.grid_level = model.level();
    fine.start.push_back(0);
    m_kappa.resize(elements.size());
    for (std::size_t e = 0; e < elements.size(); ++e) {
        const fem::HexElement& el = elements[e];
        const double d = el.rest[3] - el.rest[0]; // corner 1 is corner 0 moved +x (index-aligned frame, corner-major)
        const grid::Lame& lame = model.materials()[static_cast<std::size_t>(el.material)].lame;
        m_kappa[e] = k_calibration * element_mu(el, d, lame.lambda / lame.mu) * d;
        const Eigen::Matrix<double, 8, 1> corner_mass = el.mass.rowwise().sum();
        const double total = corner_mass.sum();
        for (int c = 0; c < 8; ++c) {
            fine.particle.push_back(el.dof_node[static_cast<std::size_t>(c)]);
            const double share = total > 0.0 ? 8.0 * corner_mass[c] / total : 1.0;
            fine.weight.push_back(m_kappa[e] * std::max(share, k_weight_floor));
        }
        fine.start.push_back(static_cast<std::uint32_t>(fine.particle.size()));
    }
    fine.rest.resize(fine.particle.size());
    for (std::size_t c = 0; c < elements.size(); ++c) finish_cluster(fine, c, rest);
    index_particles(fine, m_particles);
    m_levels.push_back(std::move(fine));

    // Coarser levels: the model elements under each element of the level.
    std::vector<std::uint32_t> ancestor(elements.size()); // per model element, its element at the level being built
    for (std::size_t e = 0; e < elements.size(); ++e) ancestor[e] = elements[e].grid_element;
    std::vector<std::uint32_t> cluster_of_element; // per model element, its cluster at the level below the one built
    for (std::size_t e = 0; e < elements.size(); ++e) cluster_of_element.push_back(static_cast<std::uint32_t>(e));
    std::vector<double> sum(m_particles, 0.0);
    std::vector<std::uint32_t> touched;
    for (int level = model.level() + 1; level <= grid.max_level() && level <= model.level() + coarse_levels; ++level) {
        const grid::Level& grid_level = grid.level(level);
        for (std::uint32_t& a : ancestor) a = grid_level.parent[a];
        // Clusters in order of their grid element; the model elements of each.
        std::vector<std::uint32_t> order(elements.size());
        for (std::uint32_t e = 0; e < order.size(); ++e) order[e] = e;
        std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return ancestor[a] < ancestor[b]; });
        ClusterLevel coarse;
        coarse.grid_level = level;
        coarse.start.push_back(0);
        ClusterLevel& below = m_levels.back();
        below.parent.assign(below.size(), grid::no_index);
        std::vector<std::uint32_t> new_cluster(elements.size());
        for (std::size_t i = 0; i < order.size();) {
            const std::uint32_t id = ancestor[order[i]];
            const auto cluster = static_cast<std::uint32_t>(coarse.size());
            for (; i < order.size() && ancestor[order[i]] == id; ++i) {
                const std::uint32_t e = order[i];
                below.parent[cluster_of_element[e]] = cluster;
                new_cluster[e] = cluster;
                const ClusterLevel& own = m_levels.front();
                for (std::uint32_t m = own.start[e]; m < own.start[e + 1]; ++m) {
                    if (sum[own.particle[m]] == 0.0) touched.push_back(own.particle[m]);
                    sum[own.particle[m]] += own.weight[m];
                }
            }
            std::sort(touched.begin(), touched.end());
            for (std::uint32_t p : touched) {
                coarse.particle.push_back(p);
                coarse.weight.push_back(sum[p]);
                sum[p] = 0.0;
            }
            touched.clear();
            coarse.start.push_back(static_cast<std::uint32_t>(coarse.particle.size()));
        }
        coarse.rest.resize(coarse.particle.size());
        for (std::size_t c = 0; c < coarse.size(); ++c) finish_cluster(coarse, c, rest);
        // A coarse cluster models the same material as its children: its weights are scaled so
        // that its rest moment (6 mu V for a cluster of material volume V: the header's kappa = mu d
        // for a cube) is theirs together. Summed as they come, the weights of a particle shared by
        // 8 children add up, and a coarse cluster was about 4 times stiffer than its children.
        std::vector<double> children(coarse.size(), 0.0);
        for (std::size_t c = 0; c < below.size(); ++c) children[below.parent[c]] += below.rest_moment[c];
        for (std::size_t c = 0; c < coarse.size(); ++c) {
            const double s = children[c] / coarse.rest_moment[c];
            for (std::uint32_t m = coarse.start[c]; m < coarse.start[c + 1]; ++m) coarse.weight[m] *= s;
            coarse.rest_moment[c] = children[c];
        }
        index_particles(coarse, m_particles);
        cluster_of_element = std::move(new_cluster);
        m_levels.push_back(std::move(coarse));
    }
    m_levels.back().parent.assign(m_levels.back().size(), grid::no_index);
}

} // namespace vox::shape
