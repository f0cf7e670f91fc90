#pragma once
// Where the picture is taken from: a camera orbiting a target (yaw about the world's up axis,
// pitch above the horizon, a distance), perspective or orthographic, framed to fit a bounding box.
// Named views for the command line: "iso" (the default), "front", "back", "left", "right",
// "top", "bottom", or "YAW,PITCH" in degrees; a trailing ",ortho" makes it orthographic.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <span>
#include <string>

namespace vox::render {

struct CameraSpec {
    double yaw_deg = 35.0, pitch_deg = 25.0; ///< 0, 0 looks along -y (the "front" of a scan)
    bool orthographic = false;
    Eigen::Vector3d up = Eigen::Vector3d::UnitZ(); ///< world up
};

/// Parses a --camera value; throws InputError naming the value and what is allowed.
[[nodiscard]] CameraSpec parse_camera(const std::string& spec);

struct Camera {
    Eigen::Vector3d eye = Eigen::Vector3d::Zero(), target = Eigen::Vector3d::Zero(), up = Eigen::Vector3d::UnitZ();
    double fov_y_deg = 30.0;      ///< perspective
    bool orthographic = false;
    double ortho_height_mm = 100; ///< visible height when orthographic
    double near_mm = 1.0, far_mm = 1000.0;

    [[nodiscard]] Eigen::Matrix4f view() const;
    /// The view's unit axes in the world: right, up (on screen) and forward (into the screen).
    void basis(Eigen::Vector3d& right, Eigen::Vector3d& screen_up, Eigen::Vector3d& forward) const;
    [[nodiscard]] Eigen::Matrix4f projection(double aspect) const;
};

/// The unit direction from what the camera looks at to the camera, for `spec`'s yaw, pitch and up.
[[nodiscard]] Eigen::Vector3d view_direction(const CameraSpec& spec);

/// A camera looking as `spec` says at `points` (world mm), centred on them and far enough for
/// all of them to fit a frame of width / height `aspect`, with a small margin.
[[nodiscard]] Camera fit_camera(const CameraSpec& spec, std::span<const Eigen::Vector3f> points, double aspect);

} // namespace vox::render
