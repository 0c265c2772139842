# The plain C scene driver (tests/fmu/fmu_scene_driver.c), built by the host build for the linux64 shared
# object and by the win64 cross build for the DLL; tests/fmu/test_win64_binary.py runs both and compares.
add_executable(fmu_scene_driver ${CMAKE_CURRENT_LIST_DIR}/fmu_scene_driver.c)
target_include_directories(fmu_scene_driver PRIVATE ${FMI2_INCLUDE_DIR} ${PROJECT_SOURCE_DIR}/model_core/include)
target_compile_options(fmu_scene_driver PRIVATE -Wall -Wextra)
target_link_libraries(fmu_scene_driver PRIVATE gimbal_master_kernel)  # its controller and base motion
set_target_properties(fmu_scene_driver PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR})
if(WIN32)
  target_link_options(fmu_scene_driver PRIVATE -static)  # no mingw runtime DLL for Wine to look for
else()
  target_link_libraries(fmu_scene_driver PRIVATE ${CMAKE_DL_LIBS} m)
endif()
