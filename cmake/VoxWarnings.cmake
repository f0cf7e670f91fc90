# One interface target carrying the project's warning flags; every module links it PRIVATE.
add_library(vox_warnings INTERFACE)
target_compile_options(vox_warnings INTERFACE
  $<$<CXX_COMPILER_ID:GNU>:-Wall -Wextra -Wpedantic -Wshadow=local -Wno-unused-parameter>
  $<$<CXX_COMPILER_ID:Clang>:-Wall -Wextra -Wpedantic -Wno-unused-parameter>) # clang (fuzz builds) has no -Wshadow=local
add_library(vox::warnings ALIAS vox_warnings)
