#include "contact/ccd_queries.hpp"

#include "core/error.hpp"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <string>

namespace vox::contact {
namespace {

/// A whole number written in decimal (optional sign), of any length, as a long double.
bool parse_integer(const std::string& text, long double& out)
{
    std::size_t i = (!text.empty() && (text[0] == '-' || text[0] == '+')) ? 1 : 0;
    if (i == text.size()) return false;
    for (std::size_t k = i; k < text.size(); ++k)
        if (!std::isdigit(static_cast<unsigned char>(text[k]))) return false;
    errno = 0;
    out = std::strtold(text.c_str(), nullptr);
    return errno == 0 && std::isfinite(out);
}

} // namespace

std::vector<CcdQuery> read_ccd_queries(const std::filesystem::path& path)
{
    const std::string name = path.string();
    if (!std::filesystem::exists(path)) throw file_error(name, "no such file");
    if (std::filesystem::is_directory(path)) throw file_error(name, "is a folder, not a query file");
    std::ifstream in(path);
    if (!in) throw file_error(name, "cannot be opened");
    std::vector<CcdQuery> queries;
    std::string line;
    std::size_t row = 0;
    while (std::getline(in, line)) {
        ++row;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (line.empty()) throw file_error(name, "line " + std::to_string(row) + ": empty line");
        std::vector<std::string> cells;
        std::size_t start = 0;
        for (std::size_t comma; (comma = line.find(',', start)) != std::string::npos; start = comma + 1)
            cells.push_back(line.substr(start, comma - start));
        cells.push_back(line.substr(start));
        if (cells.size() != 7)
            throw file_error(name, "line " + std::to_string(row) + ": expected 7 comma-separated integers, got " +
                                       std::to_string(cells.size()) + " fields");
        Eigen::Vector3d p;
        for (int axis = 0; axis < 3; ++axis) {
            long double num = 0, den = 0;
            if (!parse_integer(cells[static_cast<std::size_t>(2 * axis)], num) ||
                !parse_integer(cells[static_cast<std::size_t>(2 * axis + 1)], den))
                throw file_error(name, "line " + std::to_string(row) + ": coordinate " + std::to_string(axis + 1) + " is not a fraction of whole numbers");
            if (den == 0) throw file_error(name, "line " + std::to_string(row) + ": zero denominator");
            p[axis] = static_cast<double>(num / den);
        }
        if (cells[6] != "0" && cells[6] != "1")
            throw file_error(name, "line " + std::to_string(row) + ": the ground truth must be 0 or 1, got \"" + cells[6] + "\"");
        const std::size_t k = (row - 1) % 8;
        if (k == 0) {
            queries.emplace_back();
            queries.back().collides = cells[6] == "1";
        }
        (k < 4 ? queries.back().at0[k] : queries.back().at1[k - 4]) = p;
    }
    if (row == 0) throw file_error(name, "holds no query");
    if (row % 8 != 0) throw file_error(name, std::to_string(row) + " lines: a query takes 8 lines, the last one is cut short");
    return queries;
}

CcdScore score_ccd(const std::vector<CcdQuery>& queries, bool vertex_face, const CcdOptions& options)
{
    CcdScore s;
    for (const CcdQuery& q : queries) {
        const bool hit = vertex_face ? vertex_face_ccd(q.at0, q.at1, options) : edge_edge_ccd(q.at0, q.at1, options);
        if (hit) (q.collides ? s.true_positives : s.false_positives)++;
        else (q.collides ? s.false_negatives : s.true_negatives)++;
    }
    return s;
}

} // namespace vox::contact
