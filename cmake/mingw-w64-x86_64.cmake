# CMake tool chain for the FMU's Windows binary (binaries/win64), cross-compiled on Linux with
# Debian's mingw-w64 (package g++-mingw-w64-x86-64-win32: GCC with the win32 thread model, so no
# winpthread DLL is ever needed). The main build drives it (fmu_src/win64.cmake); by hand:
#   cmake -S . -B build-win64 -G Ninja -DCMAKE_TOOLCHAIN_FILE=cmake/mingw-w64-x86_64.cmake \
#         -DGIMBAL_WITH_SUNDIALS=OFF -DFMI2_INCLUDE_DIR=<dir of fmi2Functions.h> -DEigen3_DIR=/usr/share/eigen3/cmake
set(CMAKE_SYSTEM_NAME Windows)
set(CMAKE_SYSTEM_PROCESSOR x86_64)

set(GIMBAL_MINGW_PREFIX x86_64-w64-mingw32)
set(CMAKE_C_COMPILER ${GIMBAL_MINGW_PREFIX}-gcc)
set(CMAKE_CXX_COMPILER ${GIMBAL_MINGW_PREFIX}-g++)
set(CMAKE_RC_COMPILER ${GIMBAL_MINGW_PREFIX}-windres)

# Libraries and headers from the mingw-w64 tree only; programs (the build tools) from the host.
# Eigen is header-only and comes from the host through Eigen3_DIR, which bypasses this search.
set(CMAKE_FIND_ROOT_PATH /usr/${GIMBAL_MINGW_PREFIX})
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
