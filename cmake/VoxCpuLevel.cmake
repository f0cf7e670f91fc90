# Vector instructions. On x86-64, the code is built for AVX2 and FMA (the x86-64-v3 level, CPUs
# from 2013 on) when the machine building it has them: the simulation's inner loops (the
# preconditioner's triangular solves, the element passes) run about a third faster than with the
# baseline SSE2. VOX_PORTABLE=ON builds for any x86-64 CPU instead, e.g. for a binary that runs
# elsewhere.
option(VOX_PORTABLE "Build for any x86-64 CPU instead of the AVX2/FMA level of the building machine" OFF)

if(NOT VOX_PORTABLE AND CMAKE_SYSTEM_PROCESSOR MATCHES "^(x86_64|AMD64)$")
  include(CheckCXXSourceRuns)
  set(CMAKE_REQUIRED_FLAGS "-march=x86-64-v3")
  check_cxx_source_runs([[
    int main()
    {
        __builtin_cpu_init();
        return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") && __builtin_cpu_supports("bmi2") ? 0 : 1;
    }]] VOX_HOST_HAS_X86_64_V3)
  unset(CMAKE_REQUIRED_FLAGS)
  if(VOX_HOST_HAS_X86_64_V3)
    add_compile_options(-march=x86-64-v3)
    message(STATUS "VoxSculpt: building for x86-64-v3 (AVX2, FMA); VOX_PORTABLE=ON for any x86-64")
  else()
    message(STATUS "VoxSculpt: this CPU lacks AVX2/FMA; building for baseline x86-64")
  endif()
endif()
