#pragma once
// Haptic subdivision at the contact (after Zhang et al.'s haptic subdivision, the source paper
// haptic-subdivision-zhang.txt): around a tool's contact, the snapshot's triangles are Loop
// subdivided and their points carry a light spring layer that the 1 kHz loop steps, so the user
// feels, and could see, the surface give under the tool between simulation frames instead of a
// rigid snapshot that jumps once a frame.
//
// The layer is a membrane on an elastic foundation, per point a displacement u along its inward
// normal:
//     home springs    k_h,i = kappa a_i        (a_i the point's area: a Winkler foundation),
//     mesh springs    k_m   = kappa l^2 / sqrt(3) per fine edge (a triangular spring lattice's
//                                              membrane tension, so a load spreads over about l),
// both independent of the subdivision level, so refining samples the same continuum. The paper
// tunes its springs from an empirical table for a pure mass-spring surface; ours sits on a finite
// element model, so kappa is scaled until the layer's compliance under the contact's own load
// equals the FEM's condensed compliance there (load-weighted displacement per newton, measured by
// the method: sim::Method::contact_compliance_mm_per_n): the same force for the same
// displacement as the FEM, at any level.
//
// The snapshot already holds the deformation under the load the tool pressed with when it was
// taken, so each point's springs carry only what changed since: its preload (that load) is
// subtracted. When the tool stays, the layer stays at rest; pressing on, it gives.
//
// The handoff to the simulation, both ways. The simulation is handed the tool backed out of the
// patch by the layer's give (CoupledTool::handed_pose), so the FEM is loaded with the force the
// user feels rather than with the proxy's depth in the rigid snapshot (which, the contact being
// far stiffer than the object, would overload it and feed a frame-rate oscillation). A new
// patch starts displaced along its preload's give so the load carries on from the last patch's,
// with a carried load per point keeping that in balance; the carried load fades over
// k_handoff_s as the dynamic FEM behind the snapshots takes it up. The layer is massless: solved
// each tick, its contact linearised, by a few conjugate-gradient iterations warm started from the
// last tick.

#include "contact/penalty_contact.hpp"
#include "contact/surface_points.hpp"
#include "contact/tool_shape.hpp"

#include <Eigen/Core>

#include <span>
#include <vector>

namespace vox::contact {

struct PatchSettings {
    int levels = 1;                 ///< Loop subdivisions (0: the snapshot's own points carry the springs)
    double decay_mm = 2.0;          ///< l: how far along the surface a point load spreads
    /// The patch reaches this far beyond the contact (what the tool can slide within a frame, plus
    /// the spread), mm.
    double reach_mm = 4.0;
    /// Fewer levels where the patch would hold more (the tick's budget); no patch where the
    /// snapshot's own points there already do.
    std::size_t max_points = 600;
};

/// Builds snapshot.patch around `tool`'s contact and marks the snapshot points it stands in for
/// (simulation thread: allocates; after index()). `compliance_mm_per_n` (> 0): the FEM's
/// load-weighted displacement per newton at this contact. No contact, or no point of the surface
/// inside the patch: no patch (false).
bool build_patch(SurfacePoints& snapshot, const PlacedShape& tool, const ContactParameters& contact, double compliance_mm_per_n,
                 const PatchSettings& settings = {});

/// The compliance of a patch's springs (kappa as built) under `load` (per free point, N; any
/// sum): the load-weighted displacement per newton, mm/N. What build_patch scales to the FEM's;
/// tests read it.
[[nodiscard]] double patch_compliance(const PatchLayer& patch, std::span<const double> load);

/// The haptic thread's side of a patch: its points' displacement, stepped each tick. Sized once;
/// step() never allocates, locks or throws.
class ContactPatchState {
public:
    explicit ContactPatchState(std::size_t capacity = 4096);
    /// One tick with the tool at `tool`: the layer settles (conjugate gradients, warm started)
    /// under the contact, and the contact of the tool with the displaced patch is returned (its
    /// stiffness the contact's own: the proxy's step then approaches the layer's equilibrium from
    /// one side). A snapshot with no patch, or one too large for the capacity: zero totals.
    ContactTotals step(const PlacedShape& tool, const ContactParameters& contact, const SurfacePoints& snapshot, double dt_s = 1e-3) noexcept;
    /// The patch's free points where they are now (count: its free points).
    [[nodiscard]] const SurfacePoints& displaced() const { return m_displaced; }
    /// Per free point, how far it has given inward since the snapshot, mm.
    [[nodiscard]] std::span<const double> displacement() const { return {m_u.data(), m_displaced.count}; }
    [[nodiscard]] double max_displacement_mm() const noexcept;
    /// How far the layer gives under the tool, load-weighted, as the last step left it, mm: the
    /// simulation is handed the tool this much back from the proxy (CoupledTool::handed_pose), so
    /// the FEM is loaded with what the user feels, not with the proxy's depth in the rigid surface.
    [[nodiscard]] double give_mm() const noexcept { return m_give_mm; }
    /// Conjugate-gradient iterations a tick, at most, and the residual (the norm of the points'
    /// unbalanced forces, N) they stop at.
    static constexpr int k_iterations = 8;
    static constexpr double k_residual_n = 1e-4;
    /// A new patch carries on the load of the last (its layer displaced and a carried load in
    /// balance with it), which fades with this time constant as the FEM takes it up, s.
    static constexpr double k_handoff_s = 0.03;

private:
    /// A new patch, its points' depths measured undisplaced: starts where the last left off.
    void take_over(const PatchLayer& patch, double k_per_area) noexcept;

    SurfacePoints m_displaced;
    std::vector<double> m_u, m_distance, m_signed;
    std::vector<double> m_diagonal, m_inverse, m_r, m_p, m_ap; ///< the tick's solve, per free point
    std::vector<double> m_carried; ///< per free point, the load carried over from the last patch, N
    std::vector<double> m_measured_u; ///< per free point, its u where the tick measured its distance
    std::vector<unsigned char> m_rim; ///< per free point, whether it can end an edge the tool presses this tick
    /// A point that moves less than this in a tick keeps its linearised depth (its error is of
    /// the order of the move squared over the tool's radius of curvature), mm.
    static constexpr double k_linear_mm = 0.005;
    double m_patch_t_s = -1e300;   ///< the snapshot whose patch m_displaced holds
    bool m_had_patch = false;      ///< the last step had a patch
    double m_load_n = 0.0, m_give_mm = 0.0; ///< the last step's normal load on the layer and its give
};

} // namespace vox::contact
