#pragma once
// Closed intervals of doubles with conservative arithmetic: every result is widened by a few units
// in the last place of its bounds, more than the rounding error of the operation, so the true
// value of any expression of exact inputs inside the operands lies inside the result. (Directed
// rounding would be tighter; widening keeps the code portable and fast enough for CCD queries.)

#include <algorithm>
#include <cmath>
#include <limits>

namespace vox::contact {

struct Interval {
    double lo = 0.0, hi = 0.0;

    Interval() = default;
    constexpr Interval(double v) : lo(v), hi(v) {} // NOLINT(google-explicit-constructor): a point
    constexpr Interval(double l, double h) : lo(l), hi(h) {}

    /// The interval widened by `ulps` units of relative rounding plus the smallest normal number.
    [[nodiscard]] static Interval widened(double l, double h, double ulps = 4.0)
    {
        constexpr double u = std::numeric_limits<double>::epsilon();
        constexpr double tiny = std::numeric_limits<double>::min();
        return {l - ulps * u * std::abs(l) - tiny, h + ulps * u * std::abs(h) + tiny};
    }
    [[nodiscard]] bool contains_zero() const { return lo <= 0.0 && hi >= 0.0; }
    [[nodiscard]] bool below_zero() const { return hi < 0.0; }
};

inline Interval operator+(const Interval& a, const Interval& b) { return Interval::widened(a.lo + b.lo, a.hi + b.hi); }
inline Interval operator-(const Interval& a, const Interval& b) { return Interval::widened(a.lo - b.hi, a.hi - b.lo); }
inline Interval operator*(const Interval& a, const Interval& b)
{
    const double p[4] = {a.lo * b.lo, a.lo * b.hi, a.hi * b.lo, a.hi * b.hi};
    return Interval::widened(*std::min_element(p, p + 4), *std::max_element(p, p + 4));
}

/// a / b for a b that does not contain zero.
inline Interval operator/(const Interval& a, const Interval& b)
{
    const double q[4] = {a.lo / b.lo, a.lo / b.hi, a.hi / b.lo, a.hi / b.hi};
    return Interval::widened(*std::min_element(q, q + 4), *std::max_element(q, q + 4));
}

/// A 3-vector of intervals.
struct IVec3 {
    Interval x, y, z;
};

inline IVec3 operator+(const IVec3& a, const IVec3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline IVec3 operator-(const IVec3& a, const IVec3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline IVec3 operator*(const Interval& s, const IVec3& a) { return {s * a.x, s * a.y, s * a.z}; }
inline Interval dot(const IVec3& a, const IVec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline IVec3 cross(const IVec3& a, const IVec3& b)
{
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

} // namespace vox::contact
