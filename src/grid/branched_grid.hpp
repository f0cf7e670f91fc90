#pragma once
// The Dynamic Branched Grid (Jerabkova et al. 2010, section 2): fine voxels coarsened level by level
// into hexahedral elements. At level L the cell of voxel (i, j, k) is (i >> L, j >> L, k >> L); a
// cell holds one element per connected component (6-connectivity through connected faces) of its
// voxels, so a cell with disconnected material gets superimposed elements. Elements in
// face-adjacent cells share the four nodes of their common face exactly when a voxel of one is
// connected to a voxel of the other across it; node identity is the closure of that sharing.
// Each element's content is its fine voxels' exact moments per material (element_moments.hpp),
// built by the paper's direct condensation over Morton intervals; K and M follow from them.
//
// Removing voxels or disconnecting faces updates only the cells that hold them, level by level
// (cell removal, cell split, cell disconnect, or no topology change), and reports which old
// elements each new one came from. After any sequence of changes the grid equals a rebuild.

#include "core/eigen_types.hpp"
#include "grid/element_moments.hpp"
#include "grid/fine_voxels.hpp"
#include "grid/elastic_material.hpp"

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace vox::grid {

inline constexpr std::uint32_t no_index = ~std::uint32_t{0};

/// A connection to an element of the face-adjacent cell in `direction` (2 axis + (1 if +side)).
struct Link {
    std::uint32_t element = 0;
    std::uint8_t direction = 0;
    friend bool operator==(const Link&, const Link&) = default;
};

struct Element {
    Coord cell{0, 0, 0};                  ///< cell index at the element's level
    std::uint64_t code = 0;               ///< Morton code of the cell relative to the grid origin
    std::array<std::uint32_t, 8> nodes{}; ///< node ids; corner c has bits (+x, +y, +z)
    std::vector<std::uint32_t> voxels;    ///< its fine voxel slots, in Morton order
    std::vector<std::uint32_t> children;  ///< elements of the level below (level 1: voxel slots)
    std::vector<Link> links;              ///< connected elements of face-adjacent cells
    ElementContent content;               ///< per-material moments, cell-local
    std::uint32_t next_in_cell = no_index; ///< the next superimposed element of the same cell
    bool alive = false;
};

/// Build figures of one level, as `voxsculpt grid` reports them.
struct LevelStats {
    std::uint64_t cells = 0;
    std::uint64_t elements = 0;
    std::uint64_t nodes = 0;
    std::uint64_t condensation_steps_direct = 0;
    std::uint64_t condensation_steps_recursive = 0;
    double build_ms = 0.0;
    std::uint64_t peak_memory_bytes = 0; ///< of the whole process when the level was done
};

struct Level {
    int level = 0;
    std::vector<Element> elements;       ///< slots; dead ones (alive == false) are reused
    std::vector<std::uint32_t> free_elements;
    std::vector<std::uint32_t> released_elements; ///< removed during the current update
    CoordMap cells;                      ///< cell code -> first element of the cell
    std::vector<std::uint32_t> parent;   ///< per child of the level below (level 1: voxel slot)
    std::vector<std::uint32_t> node_users; ///< per node id: number of element corners using it
    std::vector<std::uint32_t> free_nodes;
    LevelStats stats;

    /// Elements of the cell with Morton code `code` (empty when none).
    [[nodiscard]] std::vector<std::uint32_t> cell_elements(std::uint64_t code) const;
};

/// What one batch of changes did at one level.
struct LevelChange {
    /// Elements created, each with the old elements it came from (empty for none).
    std::vector<std::pair<std::uint32_t, std::vector<std::uint32_t>>> created;
    std::vector<std::uint32_t> removed;  ///< elements that no longer exist
    std::vector<std::uint32_t> updated;  ///< elements kept with fewer voxels or other links
};
struct UpdateReport {
    std::vector<LevelChange> levels; ///< [l] for l = 1 .. max_level (index 0 unused)
};

class BranchedGrid {
public:
    struct Options {
        /// Number level 0's nodes too (8 slots per voxel: about 0.5 s and 200 MB for the liver);
        /// only reports need them, the simulation never runs at level 0 of a scan.
        bool level0_nodes = false;
    };

    /// Builds levels 1 .. max_level (at most 6) from the fine voxels, each from the one below.
    /// `materials` is indexed by FineVoxels::material().
    BranchedGrid(FineVoxels voxels, std::vector<ElasticMaterial> materials, int max_level, const Options& options);
    BranchedGrid(FineVoxels voxels, std::vector<ElasticMaterial> materials, int max_level)
        : BranchedGrid(std::move(voxels), std::move(materials), max_level, Options{})
    {
    }

    BranchedGrid(BranchedGrid&&) noexcept = default;
    BranchedGrid& operator=(BranchedGrid&&) noexcept = default;
    /// An independent copy (a trial that cuts one while the original stays as it was). Not a copy
    /// constructor, so that no grid is copied by accident.
    [[nodiscard]] BranchedGrid copy() const { return BranchedGrid(*this); }

    [[nodiscard]] const FineVoxels& voxels() const { return m_voxels; }
    [[nodiscard]] const std::vector<ElasticMaterial>& materials() const { return m_materials; }
    [[nodiscard]] int max_level() const { return static_cast<int>(m_levels.size()) - 1; }
    /// Level 1 .. max_level(); level 0 is described by level0_stats() (its elements are the voxels).
    [[nodiscard]] const Level& level(int l) const { return m_levels.at(static_cast<std::size_t>(l)); }
    /// Figures of level 0: one element and one cell per voxel; nodes counted by the same rule
    /// (0 unless Options::level0_nodes).
    [[nodiscard]] const LevelStats& level0_stats() const { return m_levels[0].stats; }

    /// Stiffness (N/m) and scalar consistent mass (kg) of element e of level l (>= 1). Full
    /// one-material cells return their level's shared matrix; partial cells are evaluated from
    /// their moments (about 10 k multiply-adds).
    [[nodiscard]] Matrix24d stiffness(int l, std::uint32_t e) const;
    [[nodiscard]] Matrix8d mass(int l, std::uint32_t e) const;
    /// True when element e of level l fills its cell with one material (it shares its matrices).
    [[nodiscard]] bool is_full(int l, std::uint32_t e) const;
    /// The element of level l (>= 1) holding the alive fine voxel v.
    [[nodiscard]] std::uint32_t element_of(std::uint32_t v, int l) const;
    /// Rest position (world mm) of every node id of level l (>= 1): the corners of the cells;
    /// ids no element uses are NaN.
    [[nodiscard]] std::vector<Eigen::Vector3d> rest_node_positions(int l) const;
    /// Index-space position of corner c of cell `cell` at level l (cells span 2^l voxels; a voxel's
    /// box is its centre +- 1/2).
    [[nodiscard]] static Eigen::Vector3d cell_corner_index(const Coord& cell, int l, int c);
    /// Sum of all fine voxels' masses, kg.
    [[nodiscard]] double total_mass_kg() const;

    /// Removes fine voxels (by source index; absent ones are ignored) and disconnects the faces
    /// between `faces[i].first` and its +axis neighbour `faces[i].second` (axis 0..2), then
    /// updates every level locally.
    UpdateReport update(std::span<const Coord> removed, std::span<const std::pair<Coord, int>> faces);

private:
    BranchedGrid(const BranchedGrid& other);
    BranchedGrid& operator=(const BranchedGrid&) = delete;
    void build_level0(bool number_nodes);
    /// (Re)builds the elements of the given cells of level l from the level below; returns what changed.
    LevelChange rebuild_cells(int l, std::vector<std::uint64_t> cell_codes, bool initial);
    /// Node ids of the grid vertices at the corners of the given cells, after a change.
    void renumber_nodes(int l, const std::vector<std::uint64_t>& cell_codes);
    /// Node ids of a whole level, at build.
    void number_all_nodes(int l);

    FineVoxels m_voxels;
    std::vector<ElasticMaterial> m_materials;
    std::vector<Level> m_levels; ///< [0] holds level 0's stats only
    std::vector<std::unique_ptr<MomentMatrices>> m_maps;
    /// Per level and material: the matrices of a full cell, shared by all full cells.
    std::vector<std::vector<Matrix24d>> m_full_stiffness;
    std::vector<std::vector<Matrix8d>> m_full_mass;
};

} // namespace vox::grid
