#pragma once
// Four doubles in one vector register, through the compiler's vector extensions (GCC, Clang): one
// AVX register on x86-64-v3, a pair of SSE2 registers on a baseline build. Arithmetic is
// element-wise, a scalar operand is broadcast, and a comparison gives a Mask (all bits set where
// true) that `cond ? a : b` selects with.

#include <cmath>
#include <cstdint>

namespace vox::fem {

using Lanes = double __attribute__((vector_size(32)));
using Mask = std::int64_t __attribute__((vector_size(32)));

[[nodiscard]] inline bool any(Mask m) { return (m[0] | m[1] | m[2] | m[3]) != 0; }

[[nodiscard]] inline Lanes lane_sqrt(Lanes x) { return Lanes{std::sqrt(x[0]), std::sqrt(x[1]), std::sqrt(x[2]), std::sqrt(x[3])}; }

[[nodiscard]] inline Lanes lane_abs(Lanes x) { return x < 0.0 ? -x : x; }

} // namespace vox::fem
