# The C kernel (built-in controllers, their set points, sensors, sums of sinusoids, the compiled communication loop)
# as a static library for the native drivers: benchmarks/bench_driver.cpp and tests/fmu_scene_driver.c
# (the latter also in the win64 cross build). The Python extension compiles the same files
# (setup.py), with the same -ffp-contract=off: a fused multiply-add would round differently.
set(_kernel_dir ${CMAKE_CURRENT_LIST_DIR})
# The sea state (numpy's seeded generator, the JONSWAP components, the sums of sinusoids on a grid):
# its own library, because the ship-motion FMU (fmu_src/ship_motion/) links it too, to give the
# scene runner's base inputs bit for bit.
add_library(gimbal_sea_state_kernel STATIC ${_kernel_dir}/numpy_random.c ${_kernel_dir}/sea_state.c
            ${_kernel_dir}/sum_of_sines.c)
target_include_directories(gimbal_sea_state_kernel PUBLIC ${_kernel_dir})
target_compile_options(gimbal_sea_state_kernel PRIVATE -Wall -Wextra -ffp-contract=off)
set_target_properties(gimbal_sea_state_kernel PROPERTIES C_VISIBILITY_PRESET hidden)
# The recorded motion (the file's table, its checks, the not-a-knot splines): its own library for the
# same reason, the ship-motion FMU reading a recording as the scene runner does.
add_library(gimbal_recorded_motion_kernel STATIC ${_kernel_dir}/cubic_spline.c ${_kernel_dir}/recorded_motion_csv.c
            ${_kernel_dir}/recorded_motion.c)
target_include_directories(gimbal_recorded_motion_kernel PUBLIC ${_kernel_dir})
target_compile_options(gimbal_recorded_motion_kernel PRIVATE -Wall -Wextra -ffp-contract=off)
set_target_properties(gimbal_recorded_motion_kernel PROPERTIES C_VISIBILITY_PRESET hidden)
add_library(gimbal_master_kernel STATIC ${_kernel_dir}/controllers.c ${_kernel_dir}/set_points.c ${_kernel_dir}/sensors.c ${_kernel_dir}/gyro.c
            ${_kernel_dir}/master_loop.c ${_kernel_dir}/layout.c)
target_include_directories(gimbal_master_kernel PUBLIC ${_kernel_dir})
target_compile_options(gimbal_master_kernel PRIVATE -Wall -Wextra -ffp-contract=off)
target_link_libraries(gimbal_master_kernel PUBLIC gimbal_sea_state_kernel)
if(NOT WIN32)
  target_link_libraries(gimbal_sea_state_kernel PUBLIC m)
  target_link_libraries(gimbal_recorded_motion_kernel PUBLIC m)
  target_link_libraries(gimbal_master_kernel PUBLIC m)
endif()
