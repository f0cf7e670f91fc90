#include "io/skull_phantom.hpp"

#include "core/error.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <vector>

namespace vox::io {
namespace {

// The head, in mm relative to its centre (LPS: +x left, +y posterior, +z superior).
constexpr double k_field_x = 180.0, k_field_y = 216.0, k_field_z = 120.0;
const Eigen::Vector3d k_centre{90.0, 110.0, 40.0};
const Eigen::Vector3d k_skull_axes{68.0, 84.0, 74.0}; ///< outer surface of the vault
constexpr double k_scalp_mm = 5.0;
constexpr double k_table_mm = 1.5;     ///< outer and inner cortical tables
constexpr double k_base_z = -30.0;     ///< the vault ends below at this height
constexpr double k_holder_gap_mm = 14.0; ///< from the skull's outer surface to the holder
constexpr double k_holder_mm = 4.0;

struct Fragment {
    Eigen::Vector3d centre;
    double radius;
};

/// Depth below the vault's outer surface along the ray from the centre (negative outside).
double depth_below_outer(const Eigen::Vector3d& p)
{
    const double rho = p.cwiseQuotient(k_skull_axes).norm();
    if (rho < 1e-9) return k_skull_axes.minCoeff();
    return p.norm() * (1.0 / rho - 1.0);
}

/// Vault thickness, mm: thicker at the back (occiput) and the top, thinner at the temples
/// (about 3 to 9 mm, as adult skulls).
double vault_thickness(const Eigen::Vector3d& p)
{
    const Eigen::Vector3d n = p.cwiseQuotient(k_skull_axes);
    return 4.5 + 3.0 * std::max(0.0, n.y()) + 1.5 * std::max(0.0, n.z()) - 1.5 * n.x() * n.x();
}

bool in_orbit(const Eigen::Vector3d& p)
{
    for (double side : {-1.0, 1.0}) {
        const Eigen::Vector3d c(side * 30.0, -0.8 * k_skull_axes.y(), -16.0);
        if ((p - c).norm() < 15.0) return true;
    }
    return false;
}

/// Small dense blobs: calcifications inside the head and specks outside it, placed by a fixed
/// generator so the phantom is the same on every machine.
std::vector<Fragment> make_fragments()
{
    std::vector<Fragment> out;
    std::uint64_t state = 0x5eed5eedULL;
    auto next = [&] { // xorshift64*: portable and exact
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        return static_cast<double>((state * 2685821657736338717ULL) >> 11) * 0x1.0p-53;
    };
    while (out.size() < 24) {
        const bool inside = out.size() < 12;
        Fragment f;
        f.radius = 1.2 + 1.8 * next();
        const Eigen::Vector3d p(next() * k_field_x, next() * k_field_y, next() * k_field_z);
        f.centre = p;
        const Eigen::Vector3d q = p - k_centre;
        const double d = depth_below_outer(q);
        const double margin = f.radius + 3.0;
        const bool keep = inside ? q.z() > k_base_z + margin && d > vault_thickness(q) + margin
                                 : d < -(k_scalp_mm + margin) && q.y() < 0.3 * k_skull_axes.y() &&
                                       (p.array() > margin).all() &&
                                       (p.array() < Eigen::Array3d(k_field_x, k_field_y, k_field_z) - margin).all();
        if (keep) out.push_back(f);
    }
    return out;
}

double hounsfield(const Eigen::Vector3d& world, const std::vector<Fragment>& fragments)
{
    for (const Fragment& f : fragments)
        if ((world - f.centre).squaredNorm() <= f.radius * f.radius) return skull_hu::fragment;
    const Eigen::Vector3d p = world - k_centre;
    // The holder: a curved sheet behind the head, a cylinder about z following the skull's outline.
    const Eigen::Vector2d inplane(p.x() / (k_skull_axes.x() + k_holder_gap_mm),
                                  p.y() / (k_skull_axes.y() + k_holder_gap_mm));
    const double holder_r = inplane.norm() * (k_skull_axes.x() + k_holder_gap_mm);
    if (p.y() > 0.7 * k_skull_axes.y() && p.z() < 0.0 && inplane.norm() >= 1.0 &&
        holder_r < k_skull_axes.x() + k_holder_gap_mm + k_holder_mm)
        return skull_hu::holder;

    const double d = depth_below_outer(p);
    const double t = vault_thickness(p);
    if (p.z() >= k_base_z) {
        if (d < -k_scalp_mm)
            return inplane.norm() < 1.0 && p.y() > 0.7 * k_skull_axes.y() && p.z() < 0.0 ? skull_hu::foam : skull_hu::air;
        if (d < 0.0) return skull_hu::soft;
        if (d <= t) {
            if (in_orbit(p)) return skull_hu::soft;
            return d < k_table_mm || d > t - k_table_mm ? skull_hu::cortical : skull_hu::diploe;
        }
        return skull_hu::brain;
    }
    // Below the vault: the neck, a soft elliptic column.
    const double neck = Eigen::Vector2d(p.x() / 48.0, (p.y() - 10.0) / 55.0).norm();
    return neck <= 1.0 ? skull_hu::soft : skull_hu::air;
}

} // namespace

Volume make_skull_phantom(const SkullPhantomSpec& spec)
{
    for (int a = 0; a < 3; ++a)
        if (!(spec.voxel_mm[a] >= 0.2 && spec.voxel_mm[a] <= 5.0))
            throw InputError("skull phantom: voxel spacing " + std::to_string(spec.voxel_mm[a]) +
                             " mm is outside [0.2, 5] mm");
    Volume v;
    const Eigen::Vector3d field(k_field_x, k_field_y, k_field_z);
    for (int a = 0; a < 3; ++a)
        v.dims[static_cast<std::size_t>(a)] = static_cast<std::int64_t>(std::floor(field[a] / spec.voxel_mm[a]));
    v.type = ScalarType::i16;
    v.index_to_world = make_index_to_world(spec.voxel_mm, Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
    v.source = "skull phantom";
    v.data.resize(static_cast<std::size_t>(v.voxel_count()) * sizeof(std::int16_t));
    const std::vector<Fragment> fragments = make_fragments();
    const auto nx = v.dims[0], ny = v.dims[1];
    tbb::parallel_for(std::int64_t{0}, v.dims[2], [&](std::int64_t k) {
        for (std::int64_t j = 0; j < ny; ++j)
            for (std::int64_t i = 0; i < nx; ++i) {
                // Partial volume: the mean of 2 x 2 x 2 samples spread over the voxel.
                double sum = 0.0;
                for (int s = 0; s < 8; ++s) {
                    const Eigen::Vector3d offset((s & 1) ? 0.25 : -0.25, (s & 2) ? 0.25 : -0.25, (s & 4) ? 0.25 : -0.25);
                    const Eigen::Vector3d index = Eigen::Vector3d(static_cast<double>(i), static_cast<double>(j),
                                                                  static_cast<double>(k)) + offset;
                    sum += hounsfield(index.cwiseProduct(spec.voxel_mm), fragments);
                }
                const auto hu = static_cast<std::int16_t>(std::lround(sum / 8.0));
                std::memcpy(v.data.data() + 2 * (i + nx * (j + ny * k)), &hu, sizeof hu);
            }
    });
    return v;
}

} // namespace vox::io
