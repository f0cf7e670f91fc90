#pragma once
// The mechanical model of one level of the branched grid: per element its nodes, condensed K and M
// (in the element's index-aligned frame), the shape-function gradients at the centroid of its
// material (where the corotational rotation is taken: reliable for partly filled elements), and
// the nodes' rest positions. SI units throughout: metres, kilograms, newtons.

#include "fem/element_shapes.hpp"
#include "core/eigen_types.hpp"
#include "grid/branched_grid.hpp"
#include "grid/mixed_levels.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <memory>
#include <vector>

namespace vox::fem {

struct HexElement {
    std::array<std::uint32_t, 8> dof_node{};   ///< dense node index (0 .. node_count-1) per corner
    /// N/m, index-aligned frame, rows and columns component-major (element_kernel.hpp: the x of
    /// corners 0..7, then y, then z); shared for full cells.
    const Matrix24d* stiffness = nullptr;
    Matrix8d mass = Matrix8d::Zero();          ///< kg, scalar consistent mass (times I3 per axis)
    Eigen::Matrix<double, 8, 3> gradient;      ///< dN_c/dX at the material centroid, 1/m, index-aligned frame
    Vector24d rest;                            ///< corner rest positions, m, index-aligned frame
    std::uint32_t grid_element = 0;            ///< the branched-grid element it models (level 0: voxel slot)
    int level = 0;                             ///< the grid level of grid_element (a model of two levels has both)
    std::int32_t material = 0;                 ///< the material holding most of its volume
    double volume_m3 = 0.0;                    ///< of its material
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero(); ///< of its material at rest, world frame, m
};

class HexModel {
public:
    /// Builds the model of `level` of `grid`: 0 (every voxel an element) .. grid.max_level().
    HexModel(const grid::BranchedGrid& grid, int level);
    /// The same after a change of the grid: elements of `previous` (the model of the same level
    /// before the change) that `changed` does not flag (per grid element id of the level: created
    /// or updated by the change) keep their stiffness and mass instead of having them evaluated
    /// from their moments again, the bulk of a rebuild after a cut. The nodes of `previous` still
    /// in use keep their order and come first.
    HexModel(const grid::BranchedGrid& grid, int level, const HexModel& previous, const std::vector<unsigned char>& changed);
    /// The model of two levels joined (grid/mixed_levels.hpp): its elements of both levels, its
    /// nodes numbered as `mixed` numbers them, and its border nodes tied to the coarse side.
    /// level() is the fine level; grid_node() holds each node's grid node at its own level
    /// (node_levels()), and dense_node() is empty. Elements of `previous`
    /// (a model of the same two levels: before the fine region moved, or before a cut) that
    /// `changed` does not flag (per level, fine then coarse, per grid element; null: none changed)
    /// keep their stiffness and mass.
    HexModel(const grid::BranchedGrid& grid, const grid::MixedLevels& mixed, const HexModel* previous = nullptr,
             const std::array<const std::vector<unsigned char>*, 2>& changed = {});

    [[nodiscard]] int level() const { return m_level; }
    /// The coarse level of a model of two levels; level() for one level.
    [[nodiscard]] int coarse_level() const { return m_coarse_level; }
    [[nodiscard]] bool mixed() const { return m_coarse_level != m_level; }
    /// Border nodes of a model of two levels, each following the coarse element beside it; empty
    /// for one level.
    [[nodiscard]] const std::vector<grid::MixedLevels::Tie>& ties() const { return m_ties; }
    /// Level of each node of a model of two levels; empty for one level.
    [[nodiscard]] const std::vector<int>& node_levels() const { return m_node_level; }
    [[nodiscard]] std::size_t node_count() const { return m_rest_world.size(); }
    [[nodiscard]] const std::vector<HexElement>& elements() const { return m_elements; }
    /// Rest positions of the nodes, world frame, m.
    [[nodiscard]] const std::vector<Eigen::Vector3d>& rest_positions() const { return m_rest_world; }
    /// Grid node id of each dense node, and the dense index of each grid node id (or no_index);
    /// empty at level 0, whose nodes exist only in this model. Two levels: the grid node at the
    /// node's own level, and no dense index.
    [[nodiscard]] const std::vector<std::uint32_t>& grid_node() const { return m_grid_node; }
    [[nodiscard]] const std::vector<std::uint32_t>& dense_node() const { return m_dense_node; }
    /// Orthonormal part of the index-to-world map: world = frame * index-aligned (a reflection
    /// when the scan's transform mirrors).
    [[nodiscard]] const Eigen::Matrix3d& frame() const { return m_frame; }
    /// Consistent mass row sums per node plus the floor below, kg (gravity acts on all of it, so
    /// that a free piece falls without bending).
    [[nodiscard]] const std::vector<double>& nodal_mass() const { return m_nodal_mass; }
    /// Lumped mass added to nodes whose share of material is tiny (a corner far from the one voxel
    /// of a partly filled element): each node weighs at least 1e-3 of a full cell's corner mass. (The
    /// same fraction of a full cell's stiffness is added to every partial element.)
    /// Without it such nodes have almost no inertia and almost no stiffness, and any solve leaves
    /// them wherever its residual stops caring. Kg per node (0 for most).
    [[nodiscard]] const std::vector<double>& added_mass() const { return m_added_mass; }
    [[nodiscard]] double total_mass() const;
    /// The grid's materials (index = HexElement::material).
    [[nodiscard]] const std::vector<grid::ElasticMaterial>& materials() const { return m_materials; }

private:
    void build_voxel_level(const grid::BranchedGrid& grid);
    void build_grid_level(const grid::BranchedGrid& grid, int level, const HexModel* previous,
                          const std::vector<unsigned char>* changed);
    /// Appends element e of grid level `level` on dense corner nodes `nodes`: its stiffness (the
    /// level's shared one from `full`, per material, when it fills its cell; else `old_stiffness`
    /// when an unchanged `old` element gives it; else evaluated), mass, rest corners and centroid.
    void add_grid_element(const grid::BranchedGrid& grid, int level, std::uint32_t e, const std::array<std::uint32_t, 8>& nodes,
                          const Matrix24d* full, const HexElement* old, std::shared_ptr<const Matrix24d> old_stiffness);
    void add_mass_floor(const grid::BranchedGrid& grid);

    int m_level = 1;
    int m_coarse_level = 1;
    std::vector<HexElement> m_elements;
    /// Per element: the stiffness a partial element owns (null for a full one), shared with the
    /// models rebuilt after later cuts while the element stays unchanged (copying them took
    /// milliseconds per cut on a CT skull's thousand partial elements).
    std::vector<std::shared_ptr<const Matrix24d>> m_partial_stiffness;
    std::vector<Matrix24d> m_full_stiffness;    ///< per material, shared by full cells
    std::vector<Eigen::Vector3d> m_rest_world;
    std::vector<std::uint32_t> m_grid_node, m_dense_node;
    std::vector<double> m_nodal_mass;
    std::vector<double> m_added_mass;
    Eigen::Matrix3d m_frame = Eigen::Matrix3d::Identity();
    std::vector<grid::ElasticMaterial> m_materials;
    std::vector<grid::MixedLevels::Tie> m_ties;
    std::vector<int> m_node_level;
};

/// The shapes of `model`'s elements at `positions` (world m, per node).
[[nodiscard]] ElementShapes element_shapes(const HexModel& model, const std::vector<Eigen::Vector3d>& positions);

} // namespace vox::fem
