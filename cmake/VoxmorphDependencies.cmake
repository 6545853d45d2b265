# Every dependency comes from Debian's packages; `run` installs them.

find_package(Eigen3 3.4 REQUIRED NO_MODULE)
find_package(ZLIB REQUIRED)
find_package(PNG REQUIRED)
find_package(nlohmann_json REQUIRED)
find_package(CLI11 REQUIRED)
find_package(Vulkan REQUIRED)
find_package(Threads REQUIRED)

find_program(GLSLANG_VALIDATOR glslangValidator REQUIRED)

# Debian's NIFTIConfig.cmake points at the wrong library directory, so the
# niftilib libraries are located directly.
find_path(NIFTI_INCLUDE_DIR nifti1_io.h PATH_SUFFIXES nifti REQUIRED)
find_library(NIFTI_IO_LIBRARY niftiio REQUIRED)
find_library(NIFTI_ZNZ_LIBRARY znz REQUIRED)
add_library(vox_nifti INTERFACE)
target_include_directories(vox_nifti SYSTEM INTERFACE ${NIFTI_INCLUDE_DIR})
target_link_libraries(vox_nifti INTERFACE ${NIFTI_IO_LIBRARY} ${NIFTI_ZNZ_LIBRARY} ZLIB::ZLIB m)

# SuiteSparse 5 ships no CMake package on Debian 12.
find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse REQUIRED)
find_library(CHOLMOD_LIBRARY cholmod REQUIRED)
find_library(SUITESPARSE_CONFIG_LIBRARY suitesparseconfig REQUIRED)
add_library(vox_cholmod INTERFACE)
target_include_directories(vox_cholmod SYSTEM INTERFACE ${CHOLMOD_INCLUDE_DIR})
target_link_libraries(vox_cholmod INTERFACE ${CHOLMOD_LIBRARY} ${SUITESPARSE_CONFIG_LIBRARY})

# LBFGS++ (liblbfgspp-dev) is header-only and ships no CMake package.
find_path(LBFGSPP_INCLUDE_DIR LBFGS.h REQUIRED)
add_library(vox_lbfgspp INTERFACE)
target_include_directories(vox_lbfgspp SYSTEM INTERFACE ${LBFGSPP_INCLUDE_DIR})

# CGAL is header-only and slow to compile: only the few translation units that
# link vox_cgal see it (see geometry/CMakeLists.txt).
set(CGAL_DATA_DIR ".")
set(CGAL_DO_NOT_WARN_ABOUT_CMAKE_BUILD_TYPE TRUE)
find_package(CGAL 5.5 REQUIRED)

# Debian's python3-nibabel and python3-meshio are installed for /usr/bin/python3.
find_program(VOXMORPH_PYTHON python3 PATHS /usr/bin NO_DEFAULT_PATH)
