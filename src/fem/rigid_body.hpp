#pragma once
// A piece of the model that moves as one rigid body (rigid material no constraint holds, or
// "unheld_pieces": "rigid"): its nodes are held in the finite-element solve and placed here,
// by a linearly implicit Euler step of the body's six degrees of freedom under gravity, loads
// and tool contact. The contact's stiffness enters the step implicitly (as it does in the
// solver), so a stiff penalty on a light fragment stays stable at the frame's dt.
//
// The body keeps no state of its own: its pose and velocity are fitted to its nodes at each step
// (exactly, as the nodes move rigidly), so a checkpoint, a recording or a rebuilt model that
// carries the nodes' positions and velocities carries the body too.

#include "fem/implicit_solver.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <span>
#include <vector>

namespace vox::fem {

class RigidBody {
public:
    /// Pose and velocity of the body: centre of mass, rotation from rest, their rates (world).
    struct State {
        Eigen::Vector3d centre = Eigen::Vector3d::Zero();
        Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
        Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
        Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();
    };

    /// The body of `nodes` (at least one), with the model's rest positions (m) and nodal masses (kg).
    RigidBody(std::vector<std::uint32_t> nodes, const std::vector<Eigen::Vector3d>& rest, const std::vector<double>& nodal_mass);

    [[nodiscard]] const std::vector<std::uint32_t>& nodes() const { return m_nodes; }
    [[nodiscard]] double mass_kg() const { return m_mass; }

    /// The pose and velocity that fit the nodes' positions and velocities best (mass-weighted
    /// least squares; exact while they move rigidly).
    [[nodiscard]] State state(const std::vector<Eigen::Vector3d>& x, const std::vector<Eigen::Vector3d>& v) const;
    [[nodiscard]] double kinetic_energy(const State& s) const;

    /// Steps `s` by dt, places the nodes (x, v) and returns the new state. `external` holds per node the loads on it
    /// (N); `contact` may list nodes of other bodies, which are ignored. `damping_per_s` is the
    /// mass-proportional Rayleigh damping of the scene.
    State advance(const State& s, double dt, double damping_per_s, const Eigen::Vector3d& gravity,
                 const std::vector<Eigen::Vector3d>& external, std::span<const NodeContact> contact,
                 const std::vector<std::int32_t>& body_of_node, std::int32_t self, std::vector<Eigen::Vector3d>& x,
                 std::vector<Eigen::Vector3d>& v) const;

private:
    [[nodiscard]] Eigen::Matrix3d world_inertia(const Eigen::Matrix3d& rotation) const;

    std::vector<std::uint32_t> m_nodes;
    std::vector<Eigen::Vector3d> m_offset; ///< per node: rest position minus the rest centre of mass, m
    std::vector<double> m_node_mass;
    double m_mass = 0.0;
    Eigen::Matrix3d m_inertia = Eigen::Matrix3d::Zero(); ///< about the centre of mass, rest orientation, kg m^2
};

} // namespace vox::fem
