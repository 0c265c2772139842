# FMU states handed over by careless or hostile importers (tests/fmu/test_fmu_states.cpp), and the host's
# floating-point environment and repeated loading (tests/fmu/test_host_environment.cpp): both drive the
# built FMU through dlopen.
add_executable(test_fmu_states ${CMAKE_CURRENT_LIST_DIR}/test_fmu_states.cpp ${PROJECT_SOURCE_DIR}/fmu_src/fmi_layer/fmu_state.c)
target_include_directories(test_fmu_states PRIVATE ${FMI2_INCLUDE_DIR} ${PROJECT_SOURCE_DIR}/fmu_src)
target_link_libraries(test_fmu_states PRIVATE ${CMAKE_DL_LIBS})
add_dependencies(test_fmu_states fmu)
add_test(NAME fmu_states
         COMMAND test_fmu_states ${PROJECT_BINARY_DIR}/fmu_staging/binaries/linux64/${MODEL_IDENTIFIER}.so
                 ${PROJECT_BINARY_DIR}/fmu_staging/modelDescription.xml)
set_tests_properties(fmu_states PROPERTIES TIMEOUT 600)

add_executable(test_host_environment ${CMAKE_CURRENT_LIST_DIR}/test_host_environment.cpp)
# GIMBAL_EVENT_INDICATORS: the count of the switching elements' declaration (gimbal/switching_elements.def).
target_include_directories(test_host_environment PRIVATE ${FMI2_INCLUDE_DIR} ${PROJECT_SOURCE_DIR}/model_core/include)
target_link_libraries(test_host_environment PRIVATE ${CMAKE_DL_LIBS})
add_dependencies(test_host_environment fmu)
add_test(NAME host_environment
         COMMAND test_host_environment ${PROJECT_BINARY_DIR}/fmu_staging/binaries/linux64/${MODEL_IDENTIFIER}.so
                 ${PROJECT_BINARY_DIR}/fmu_staging/modelDescription.xml)
set_tests_properties(host_environment PROPERTIES TIMEOUT 300)
