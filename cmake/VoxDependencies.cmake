# Finds every dependency from its Debian package (see scripts/install-deps.sh).

# TBB in CONFIG mode first: OpenVDB's bundled FindTBB would otherwise define TBB::tbb itself
# and a later config lookup would fail on half-defined targets.
find_package(TBB CONFIG REQUIRED)
# Debian ships OpenVDB's Find module only, not a config package.
list(APPEND CMAKE_MODULE_PATH /usr/lib/x86_64-linux-gnu/cmake/OpenVDB /usr/lib/cmake/OpenVDB)
find_package(OpenVDB REQUIRED)
find_package(Imath CONFIG REQUIRED)

find_package(Eigen3 3.3 CONFIG REQUIRED NO_MODULE)
find_package(OpenMesh CONFIG REQUIRED)
find_package(nlohmann_json 3 CONFIG REQUIRED)
find_package(CLI11 CONFIG REQUIRED)
find_package(spdlog CONFIG REQUIRED)
find_package(ZLIB REQUIRED)
find_package(Threads REQUIRED)

# NIfTI: Debian's NIFTIConfig.cmake points at a wrong libznz path, so find it by hand.
# Link libnifti2 only (never with libniftiio: same symbols, other ABI).
find_path(NIFTI2_INCLUDE_DIR nifti2_io.h PATH_SUFFIXES nifti REQUIRED)
find_library(NIFTI2_LIBRARY nifti2 REQUIRED)
find_library(ZNZ_LIBRARY znz REQUIRED)
add_library(vox_nifti2 INTERFACE)
target_include_directories(vox_nifti2 SYSTEM INTERFACE ${NIFTI2_INCLUDE_DIR})
target_link_libraries(vox_nifti2 INTERFACE ${NIFTI2_LIBRARY} ${ZNZ_LIBRARY} ZLIB::ZLIB m)
add_library(vox::nifti2 ALIAS vox_nifti2)

# DICOM series (io/dicom_reader.cpp only): GDCM's image library, with its JPEG, JPEG-LS (CharLS)
# and JPEG 2000 (OpenJPEG) decoders.
find_package(GDCM 3 REQUIRED)
add_library(vox_gdcm INTERFACE)
target_include_directories(vox_gdcm SYSTEM INTERFACE ${GDCM_INCLUDE_DIRS})
target_link_libraries(vox_gdcm INTERFACE gdcmMSFF)
add_library(vox::gdcm ALIAS vox_gdcm)

# CHOLMOD (SuiteSparse) for the supernodal Cholesky preconditioner; Debian ships no CMake package
# for SuiteSparse 5, so find it by hand. BLAS comes with it (OpenBLAS, serial, when installed).
find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse REQUIRED)
find_library(CHOLMOD_LIBRARY cholmod REQUIRED)
add_library(vox_cholmod INTERFACE)
target_include_directories(vox_cholmod SYSTEM INTERFACE ${CHOLMOD_INCLUDE_DIR})
target_link_libraries(vox_cholmod INTERFACE ${CHOLMOD_LIBRARY})
add_library(vox::cholmod ALIAS vox_cholmod)

if(VOX_BUILD_TESTS)
  find_package(GTest CONFIG REQUIRED)
endif()

# Used by the render and haptics modules; found here so a configure checks the whole toolchain.
find_package(glfw3 3.3 CONFIG REQUIRED)
find_package(glm CONFIG REQUIRED)
find_package(PkgConfig REQUIRED)
pkg_check_modules(HIDAPI REQUIRED IMPORTED_TARGET hidapi-hidraw)
