#pragma once
// The pieces an object is in: groups of elements joined through shared nodes. A through-cut
// leaves two.

#include "fem/hex_model.hpp"

#include <vector>

namespace vox::cut {

/// Piece number (0, 1, ...) of every model element; pieces are numbered in order of their
/// lowest element.
[[nodiscard]] std::vector<std::uint32_t> element_pieces(const fem::HexModel& model);
/// The number of pieces.
[[nodiscard]] std::size_t piece_count(const fem::HexModel& model);
/// Per element: 1 when no node of its piece is flagged in `held` (per node), i.e. no constraint
/// reaches the piece; `count` receives how many such pieces there are.
[[nodiscard]] std::vector<unsigned char> unheld_elements(const fem::HexModel& model, const std::vector<unsigned char>& held,
                                                         std::size_t& count);

} // namespace vox::cut
