#include "render/camera.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <span>

namespace vox::render {

CameraSpec parse_camera(const std::string& spec)
{
    CameraSpec c;
    std::string view = spec;
    const std::string ortho = ",ortho";
    if (view.size() >= ortho.size() && view.compare(view.size() - ortho.size(), ortho.size(), ortho) == 0) {
        c.orthographic = true;
        view.resize(view.size() - ortho.size());
    }
    struct Named {
        const char* name;
        double yaw, pitch;
    };
    static constexpr Named named[] = {{"iso", 35, 25},   {"front", 0, 0},  {"back", 180, 0},  {"left", -90, 0},
                                      {"right", 90, 0},  {"top", 0, 89.9}, {"bottom", 0, -89.9}};
    for (const Named& n : named)
        if (view == n.name) {
            c.yaw_deg = n.yaw;
            c.pitch_deg = n.pitch;
            return c;
        }
    std::istringstream in(view);
    char comma = 0;
    double yaw = 0, pitch = 0;
    if (in >> yaw >> comma >> pitch && comma == ',' && in.peek() == std::char_traits<char>::eof() && std::abs(pitch) <= 90.0) {
        c.yaw_deg = yaw;
        c.pitch_deg = std::clamp(pitch, -89.9, 89.9);
        return c;
    }
    throw InputError("--camera \"" + spec + "\": expected iso, front, back, left, right, top, bottom or YAW,PITCH in degrees "
                     "(pitch within +-90), optionally followed by \",ortho\"");
}

void Camera::basis(Eigen::Vector3d& right, Eigen::Vector3d& screen_up, Eigen::Vector3d& forward) const
{
    forward = (target - eye).normalized();
    right = forward.cross(up).normalized();
    screen_up = right.cross(forward);
}

Eigen::Matrix4f Camera::view() const
{
    Eigen::Vector3d s, u, f;
    basis(s, u, f);
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    m.block<1, 3>(0, 0) = s.transpose();
    m.block<1, 3>(1, 0) = u.transpose();
    m.block<1, 3>(2, 0) = -f.transpose();
    m(0, 3) = -s.dot(eye);
    m(1, 3) = -u.dot(eye);
    m(2, 3) = f.dot(eye);
    return m.cast<float>();
}

Eigen::Matrix4f Camera::projection(double aspect) const
{
    Eigen::Matrix4d p = Eigen::Matrix4d::Zero();
    if (orthographic) {
        const double h = 0.5 * ortho_height_mm, w = h * aspect;
        p(0, 0) = 1.0 / w;
        p(1, 1) = 1.0 / h;
        p(2, 2) = -2.0 / (far_mm - near_mm);
        p(2, 3) = -(far_mm + near_mm) / (far_mm - near_mm);
        p(3, 3) = 1.0;
    } else {
        const double t = 1.0 / std::tan(0.5 * fov_y_deg * M_PI / 180.0);
        p(0, 0) = t / aspect;
        p(1, 1) = t;
        p(2, 2) = -(far_mm + near_mm) / (far_mm - near_mm);
        p(2, 3) = -2.0 * far_mm * near_mm / (far_mm - near_mm);
        p(3, 2) = -1.0;
    }
    return p.cast<float>();
}

Eigen::Vector3d view_direction(const CameraSpec& spec)
{
    // Yaw about up, pitch above the horizon; yaw 0 looks along -y, from the -y side (the front of
    // a scan in patient coordinates faces -y), for up = +z; other ups turn that frame.
    const double yaw = spec.yaw_deg * M_PI / 180.0, pitch = spec.pitch_deg * M_PI / 180.0;
    const Eigen::Vector3d back(std::sin(yaw) * std::cos(pitch), -std::cos(yaw) * std::cos(pitch), std::sin(pitch));
    return spec.up == Eigen::Vector3d::UnitZ() ? back : Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), spec.up) * back;
}

Camera fit_camera(const CameraSpec& spec, std::span<const Eigen::Vector3f> points, double aspect)
{
    Camera c;
    c.orthographic = spec.orthographic;
    c.up = spec.up;
    Eigen::AlignedBox3d bounds;
    bounds.setEmpty();
    for (const Eigen::Vector3f& p : points) bounds.extend(p.cast<double>());
    if (bounds.isEmpty()) bounds.extend(Eigen::Vector3d::Zero());
    const double radius = std::max(0.5 * bounds.diagonal().norm(), 1e-3);
    const Eigen::Vector3d back = view_direction(spec);
    const Eigen::Vector3d right = (-back).cross(c.up).normalized(), up = right.cross(-back);
    // Centre the points' extent across the view, then step back until every point is in the
    // frame with 10 % of margin (the points themselves, not their box: a round object fills
    // little of its box's outline).
    double x_lo = 1e300, x_hi = -1e300, y_lo = 1e300, y_hi = -1e300;
    const Eigen::Vector3d centre = bounds.center();
    for (const Eigen::Vector3f& pf : points) {
        const Eigen::Vector3d d = pf.cast<double>() - centre;
        x_lo = std::min(x_lo, d.dot(right));
        x_hi = std::max(x_hi, d.dot(right));
        y_lo = std::min(y_lo, d.dot(up));
        y_hi = std::max(y_hi, d.dot(up));
    }
    if (points.empty()) x_lo = x_hi = y_lo = y_hi = 0.0;
    c.target = centre + 0.5 * (x_lo + x_hi) * right + 0.5 * (y_lo + y_hi) * up;
    const double tan_v = std::tan(0.5 * c.fov_y_deg * M_PI / 180.0), tan_h = tan_v * aspect;
    double distance = 0.0, half_height = 1e-3;
    for (const Eigen::Vector3f& pf : points) {
        const Eigen::Vector3d d = pf.cast<double>() - c.target;
        const double x = 1.1 * std::abs(d.dot(right)), y = 1.1 * std::abs(d.dot(up)), z = d.dot(back);
        half_height = std::max({half_height, y, x / aspect});
        distance = std::max({distance, z + y / tan_v, z + x / tan_h});
    }
    if (c.orthographic) {
        c.ortho_height_mm = 2.0 * half_height;
        distance = 3.0 * radius;
    }
    distance = std::max(distance, 1e-2 * radius);
    c.eye = c.target + distance * back;
    c.near_mm = std::max(1e-3 * distance, distance - 2.2 * radius);
    c.far_mm = distance + 2.2 * radius;
    return c;
}

} // namespace vox::render
