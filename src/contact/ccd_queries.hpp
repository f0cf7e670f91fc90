#pragma once
// Query files of the continuous-collision benchmark of Wang, Ferguson, Schneider, Jiang, Attene
// and Panozzo 2021 (data/ccd-queries/README.md): 8 rows per query, each row one point as three
// rational coordinates (numerator, denominator pairs, integers that may exceed 64 bits) and the
// query's ground truth (0 or 1). Coordinates are read as doubles.

#include "contact/ccd.hpp"

#include <filesystem>
#include <vector>

namespace vox::contact {

struct CcdQuery {
    std::array<Eigen::Vector3d, 4> at0, at1;
    bool collides = false; ///< the ground truth
};

/// Throws InputError naming the file and line for anything malformed.
[[nodiscard]] std::vector<CcdQuery> read_ccd_queries(const std::filesystem::path& path);

struct CcdScore {
    std::size_t true_positives = 0, false_positives = 0, false_negatives = 0, true_negatives = 0;
};

/// Runs every query through vertex_face_ccd (vertex_face = true) or edge_edge_ccd.
[[nodiscard]] CcdScore score_ccd(const std::vector<CcdQuery>& queries, bool vertex_face, const CcdOptions& options = {});

} // namespace vox::contact
