# Out-of-memory test (issue 12): tests/fmu/oom_shim.c, preloaded, fails the n-th allocation of a full FMU
# lifecycle, for every n; tests/fmu/test_out_of_memory.cpp drives the FMU's shared object through it.
#
# Not with GIMBAL_SANITIZE: AddressSanitizer replaces malloc itself, and its runtime must come first
# in the process, so the shim could neither be preloaded alongside it nor see the FMU's allocations.
if(GIMBAL_SANITIZE)
  return()
endif()

add_library(oom_shim SHARED ${CMAKE_CURRENT_LIST_DIR}/oom_shim.c)
target_compile_options(oom_shim PRIVATE -Wall -Wextra)
set_target_properties(oom_shim PROPERTIES C_VISIBILITY_PRESET hidden)

add_executable(test_out_of_memory ${CMAKE_CURRENT_LIST_DIR}/test_out_of_memory.cpp)
target_include_directories(test_out_of_memory PRIVATE ${FMI2_INCLUDE_DIR} ${PROJECT_SOURCE_DIR}/model_core/include)
target_compile_options(test_out_of_memory PRIVATE -Wall -Wextra)
target_link_libraries(test_out_of_memory PRIVATE ${CMAKE_DL_LIBS})
add_dependencies(test_out_of_memory fmu fmu3 oom_shim)

add_test(NAME out_of_memory
         COMMAND test_out_of_memory ${PROJECT_BINARY_DIR}/fmu_staging/binaries/linux64/${MODEL_IDENTIFIER}.so
                 ${PROJECT_BINARY_DIR}/fmu_staging/modelDescription.xml)
set_tests_properties(out_of_memory PROPERTIES TIMEOUT 300 ENVIRONMENT "LD_PRELOAD=$<TARGET_FILE:oom_shim>")

# The FMI 3.0 binary's lifecycle (method 101: Co-Simulation with Event Mode and early returns, then
# Model Exchange), with the FMI 2.0 description for the value references (the same Reals).
add_test(NAME out_of_memory_fmi3
         COMMAND test_out_of_memory ${PROJECT_BINARY_DIR}/fmi3/binary/${MODEL_IDENTIFIER}.so
                 ${PROJECT_BINARY_DIR}/fmu_staging/modelDescription.xml 101)
set_tests_properties(out_of_memory_fmi3 PROPERTIES TIMEOUT 300 ENVIRONMENT "LD_PRELOAD=$<TARGET_FILE:oom_shim>")
