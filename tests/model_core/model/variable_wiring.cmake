# Issue 12: every variable reaches the field of its name, whatever the order of the .def tables.
add_executable(test_variable_wiring ${CMAKE_CURRENT_LIST_DIR}/test_variable_wiring.cpp)
target_link_libraries(test_variable_wiring PRIVATE gimbal_core)
add_test(NAME variable_wiring COMMAND test_variable_wiring)
