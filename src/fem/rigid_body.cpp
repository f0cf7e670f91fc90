#include "fem/rigid_body.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

#include <stdexcept>

namespace vox::fem {
namespace {

Eigen::Matrix3d cross_matrix(const Eigen::Vector3d& r)
{
    Eigen::Matrix3d m;
    m << 0.0, -r.z(), r.y(), r.z(), 0.0, -r.x(), -r.y(), r.x(), 0.0;
    return m;
}

} // namespace

RigidBody::RigidBody(std::vector<std::uint32_t> nodes, const std::vector<Eigen::Vector3d>& rest, const std::vector<double>& nodal_mass)
    : m_nodes(std::move(nodes))
{
    if (m_nodes.empty()) throw std::invalid_argument("RigidBody: no nodes");
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (std::uint32_t n : m_nodes) {
        m_node_mass.push_back(nodal_mass[n]);
        m_mass += nodal_mass[n];
        centre += nodal_mass[n] * rest[n];
    }
    centre /= m_mass;
    for (std::size_t k = 0; k < m_nodes.size(); ++k) {
        const Eigen::Vector3d r = rest[m_nodes[k]] - centre;
        m_offset.push_back(r);
        m_inertia += m_node_mass[k] * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose());
    }
}

Eigen::Matrix3d RigidBody::world_inertia(const Eigen::Matrix3d& rotation) const
{
    return rotation * m_inertia * rotation.transpose();
}

RigidBody::State RigidBody::state(const std::vector<Eigen::Vector3d>& x, const std::vector<Eigen::Vector3d>& v) const
{
    State s;
    for (std::size_t k = 0; k < m_nodes.size(); ++k) {
        s.centre += m_node_mass[k] * x[m_nodes[k]];
        s.velocity += m_node_mass[k] * v[m_nodes[k]];
    }
    s.centre /= m_mass;
    s.velocity /= m_mass;
    // Rotation: the orthogonal part of the mass-weighted covariance of current and rest offsets
    // (Kabsch), a reflection turned into a rotation.
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    Eigen::Vector3d momentum = Eigen::Vector3d::Zero();
    for (std::size_t k = 0; k < m_nodes.size(); ++k) {
        const Eigen::Vector3d r = x[m_nodes[k]] - s.centre;
        covariance += m_node_mass[k] * r * m_offset[k].transpose();
        momentum += m_node_mass[k] * r.cross(v[m_nodes[k]] - s.velocity);
    }
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(covariance, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
    d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
    s.rotation = svd.matrixU() * d * svd.matrixV().transpose();
    // A body of collinear nodes has a singular inertia: no spin about that line (the symmetric
    // pseudo-inverse).
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> inertia(world_inertia(s.rotation));
    Eigen::Vector3d inverse = inertia.eigenvalues();
    const double tiny = 1e-12 * inverse.cwiseAbs().maxCoeff();
    for (int i = 0; i < 3; ++i) inverse[i] = inverse[i] > tiny ? 1.0 / inverse[i] : 0.0;
    s.angular_velocity = inertia.eigenvectors() * inverse.asDiagonal() * (inertia.eigenvectors().transpose() * momentum);
    return s;
}

double RigidBody::kinetic_energy(const State& s) const
{
    return 0.5 * m_mass * s.velocity.squaredNorm() + 0.5 * s.angular_velocity.dot(world_inertia(s.rotation) * s.angular_velocity);
}

RigidBody::State RigidBody::advance(const State& s, double dt, double damping_per_s, const Eigen::Vector3d& gravity,
                                   const std::vector<Eigen::Vector3d>& external, std::span<const NodeContact> contact,
                                   const std::vector<std::int32_t>& body_of_node, std::int32_t self, std::vector<Eigen::Vector3d>& x,
                                   std::vector<Eigen::Vector3d>& v) const
{
    // Implicit Euler on (v, w): (1 + alpha dt) M6 P' + dt^2 sum J^T K J P' = M6 P + dt (F + gyroscopic),
    // J = [I, -[r]x] mapping P to a point's velocity, K the contact stiffness at that point.
    const Eigen::Matrix3d inertia = world_inertia(s.rotation);
    Eigen::Matrix<double, 6, 6> mass6 = Eigen::Matrix<double, 6, 6>::Zero();
    mass6.topLeftCorner<3, 3>() = m_mass * Eigen::Matrix3d::Identity();
    mass6.bottomRightCorner<3, 3>() = inertia;
    Eigen::Matrix<double, 6, 1> p;
    p << s.velocity, s.angular_velocity;
    Eigen::Vector3d force = m_mass * gravity;
    Eigen::Vector3d torque = -s.angular_velocity.cross(inertia * s.angular_velocity);
    for (std::size_t k = 0; k < m_nodes.size(); ++k) {
        const Eigen::Vector3d& f = external[m_nodes[k]];
        force += f;
        torque += (x[m_nodes[k]] - s.centre).cross(f);
    }
    Eigen::Matrix<double, 6, 6> a = (1.0 + dt * damping_per_s) * mass6;
    for (const NodeContact& c : contact) {
        if (body_of_node[c.node] != self) continue;
        const Eigen::Vector3d r = x[c.node] - s.centre;
        Eigen::Matrix<double, 3, 6> j;
        j << Eigen::Matrix3d::Identity(), -cross_matrix(r);
        force += c.force_n;
        torque += r.cross(c.force_n);
        a.noalias() += dt * dt * j.transpose() * c.stiffness_n_per_m * j;
    }
    Eigen::Matrix<double, 6, 1> b = mass6 * p;
    b.head<3>() += dt * force;
    b.tail<3>() += dt * torque;
    const Eigen::Matrix<double, 6, 1> next = a.completeOrthogonalDecomposition().solve(b);
    const Eigen::Vector3d velocity = next.head<3>(), spin = next.tail<3>();
    const Eigen::Vector3d centre = s.centre + dt * velocity;
    Eigen::Matrix3d rotation = s.rotation;
    if (const double angle = dt * spin.norm(); angle > 0.0)
        rotation = Eigen::AngleAxisd(angle, spin.normalized()).toRotationMatrix() * s.rotation;
    for (std::size_t k = 0; k < m_nodes.size(); ++k) {
        const Eigen::Vector3d r = rotation * m_offset[k];
        x[m_nodes[k]] = centre + r;
        v[m_nodes[k]] = velocity + spin.cross(r);
    }
    return {centre, rotation, velocity, spin};
}

} // namespace vox::fem
