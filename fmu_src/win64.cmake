# The FMU's Windows binary, cross-compiled with mingw-w64: a second configure of this source tree
# with cmake/mingw-w64-x86_64.cmake in build/win64, driven from this build as an ExternalProject.
# Why a second build: a CMake build has one compiler per language, and the cross build needs its own
# (and its own GIMBAL_WITH_SUNDIALS=OFF: Debian has no mingw-w64 SUNDIALS); why driven from here:
# one `cmake --build` makes the one FMU with both binaries, and the inner Ninja build tracks its own
# sources (BUILD_ALWAYS only hands over to it; with nothing changed it does nothing).
# Sets GIMBAL_BUILD_WIN64, GIMBAL_WIN64_DLL, GIMBAL_WIN64_FMI3_DLL (the FMI 3.0 binary) and
# GIMBAL_WIN64_DRIVER (fmu_scene_driver.exe, for the tests), GIMBAL_WIN64_SHIP_DLL and
# GIMBAL_WIN64_CONTROLLER_DLL (the ship-motion and controller FMUs' binaries), GIMBAL_WIN64_SHIP3_DLL and
# GIMBAL_WIN64_CONTROLLER3_DLL (their FMI 3.0 binaries).
set(GIMBAL_BUILD_WIN64 OFF)
if(GIMBAL_WIN64 STREQUAL "AUTO")
  find_program(GIMBAL_MINGW_CXX x86_64-w64-mingw32-g++)
  if(GIMBAL_MINGW_CXX AND NOT GIMBAL_SANITIZE)
    set(GIMBAL_BUILD_WIN64 ON)
  endif()
elseif(GIMBAL_WIN64)
  find_program(GIMBAL_MINGW_CXX x86_64-w64-mingw32-g++)
  if(NOT GIMBAL_MINGW_CXX)
    message(FATAL_ERROR "GIMBAL_WIN64=ON needs the mingw-w64 tool chain (Debian: g++-mingw-w64-x86-64-win32)")
  endif()
  set(GIMBAL_BUILD_WIN64 ON)
endif()
if(NOT GIMBAL_BUILD_WIN64)
  message(STATUS "binaries/win64: not built (GIMBAL_WIN64=${GIMBAL_WIN64}, mingw-w64 g++: ${GIMBAL_MINGW_CXX})")
  return()
endif()
message(STATUS "binaries/win64: cross-compiled with ${GIMBAL_MINGW_CXX} in ${PROJECT_BINARY_DIR}/win64")

include(ExternalProject)
set(_win64_dir ${PROJECT_BINARY_DIR}/win64)
set(GIMBAL_WIN64_DLL ${_win64_dir}/fmu_src/${MODEL_IDENTIFIER}.dll)
set(GIMBAL_WIN64_DRIVER ${_win64_dir}/fmu_scene_driver.exe)
set(GIMBAL_WIN64_FMI3_DLL ${_win64_dir}/fmi3/binary/${MODEL_IDENTIFIER}.dll)
set(GIMBAL_WIN64_SHIP_DLL ${_win64_dir}/fmu_src/ship_motion/${SHIP_MODEL_IDENTIFIER}.dll)
set(GIMBAL_WIN64_CONTROLLER_DLL ${_win64_dir}/fmu_src/controller/${CONTROLLER_MODEL_IDENTIFIER}.dll)
set(GIMBAL_WIN64_SHIP3_DLL ${_win64_dir}/fmu_src/ship_motion/fmi3/${SHIP_MODEL_IDENTIFIER}.dll)
set(GIMBAL_WIN64_CONTROLLER3_DLL ${_win64_dir}/fmu_src/controller/fmi3/${CONTROLLER_MODEL_IDENTIFIER}.dll)
ExternalProject_Add(gimbal_win64
  SOURCE_DIR ${PROJECT_SOURCE_DIR}
  BINARY_DIR ${_win64_dir}
  CMAKE_ARGS
    -DCMAKE_TOOLCHAIN_FILE=${PROJECT_SOURCE_DIR}/cmake/mingw-w64-x86_64.cmake
    -DCMAKE_BUILD_TYPE=Release
    -DGIMBAL_WITH_SUNDIALS=OFF
    -DFMI2_INCLUDE_DIR=${FMI2_INCLUDE_DIR}
    -DEigen3_DIR=${Eigen3_DIR}
  INSTALL_COMMAND ""
  BUILD_ALWAYS ON
  BUILD_BYPRODUCTS ${GIMBAL_WIN64_DLL} ${GIMBAL_WIN64_DRIVER} ${GIMBAL_WIN64_FMI3_DLL} ${GIMBAL_WIN64_SHIP_DLL}
                   ${GIMBAL_WIN64_CONTROLLER_DLL} ${GIMBAL_WIN64_SHIP3_DLL} ${GIMBAL_WIN64_CONTROLLER3_DLL})
