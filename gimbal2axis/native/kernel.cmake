# The C kernel (built-in controllers, their set points, sensors, sums of sinusoids, the compiled communication loop)
# as a static library for the native drivers: benchmarks/bench_driver.cpp and tests/fmu_scene_driver.c
# (the latter also in the win64 cross build). The Python extension compiles the same files
# (setup.py), with the same -ffp-contract=off: a fused multiply-add would round differently.
set(_kernel_dir ${CMAKE_CURRENT_LIST_DIR})
add_library(gimbal_master_kernel STATIC ${_kernel_dir}/controllers.c ${_kernel_dir}/set_points.c ${_kernel_dir}/sensors.c ${_kernel_dir}/gyro.c
            ${_kernel_dir}/sum_of_sines.c ${_kernel_dir}/master_loop.c ${_kernel_dir}/layout.c)
target_include_directories(gimbal_master_kernel PUBLIC ${_kernel_dir})
target_compile_options(gimbal_master_kernel PRIVATE -Wall -Wextra -ffp-contract=off)
if(NOT WIN32)
  target_link_libraries(gimbal_master_kernel PUBLIC m)
endif()
