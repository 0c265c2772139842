# build/Gimbal2Axis-ShipMotion.fmu: modelDescription.xml from the variable table (the generator's
# fragments in modelDescription.xml.in), binaries/linux64 and, with mingw-w64, binaries/win64
# (fmu_src/win64.cmake builds it), the project's licence in documentation/licenses/, the example
# recording (recording_file's start value) in resources/.
set(_ship_dir ${CMAKE_CURRENT_LIST_DIR})
set(_ship_staging ${PROJECT_BINARY_DIR}/ship_motion_staging)
set(_ship_fragments ${PROJECT_BINARY_DIR}/ship_motion_fragments)
set(SHIP_MOTION_FMU ${PROJECT_BINARY_DIR}/Gimbal2Axis-ShipMotion.fmu)
set(_ship_recording ${_ship_dir}/resources/ship_recording.csv)
add_custom_command(
  OUTPUT ${_ship_staging}/modelDescription.xml
  COMMAND ${CMAKE_COMMAND} -E make_directory ${_ship_fragments} ${_ship_staging}
  COMMAND ship_motion_model_description_generator ${_ship_fragments}/units.xml ${_ship_fragments}/variables.xml
          ${_ship_fragments}/structure.xml
  COMMAND ${CMAKE_COMMAND}
    -DTEMPLATE=${_ship_dir}/modelDescription.xml.in
    -DOUTPUT=${_ship_staging}/modelDescription.xml
    -DFRAGMENTS=${_ship_fragments}
    -DSHIP_MODEL_IDENTIFIER=${SHIP_MODEL_IDENTIFIER}
    -DSHIP_MOTION_GUID=${SHIP_MOTION_GUID}
    -DPROJECT_NAME=${PROJECT_NAME}
    -DPROJECT_VERSION=${PROJECT_VERSION}
    "-DGIMBAL_AUTHOR=${GIMBAL_AUTHOR}"
    "-DGIMBAL_COPYRIGHT=${GIMBAL_COPYRIGHT}"
    "-DGIMBAL_LICENSE=${GIMBAL_LICENSE}"
    -DSOURCE_DIR=${PROJECT_SOURCE_DIR}
    -DGIT_EXECUTABLE=${GIT_EXECUTABLE}
    -P ${_ship_dir}/configure_model_description.cmake
  DEPENDS ship_motion_model_description_generator ${_ship_dir}/modelDescription.xml.in
          ${_ship_dir}/configure_model_description.cmake ${GIMBAL_HEAD_LOG}
  COMMENT "Configuring the ship-motion FMU's modelDescription.xml"
  VERBATIM)

if(GIMBAL_BUILD_WIN64)
  set(_ship_win64_commands
    COMMAND ${CMAKE_COMMAND} -E make_directory ${_ship_staging}/binaries/win64
    COMMAND ${CMAKE_COMMAND} -E copy ${GIMBAL_WIN64_SHIP_DLL} ${_ship_staging}/binaries/win64/${SHIP_MODEL_IDENTIFIER}.dll)
  set(_ship_win64_depends gimbal_win64 ${GIMBAL_WIN64_SHIP_DLL})
else()
  set(_ship_win64_commands COMMAND ${CMAKE_COMMAND} -E rm -rf ${_ship_staging}/binaries/win64)
  set(_ship_win64_depends "")
endif()
add_custom_command(
  OUTPUT ${SHIP_MOTION_FMU}
  COMMAND ${CMAKE_COMMAND} -E make_directory ${_ship_staging}/binaries/linux64 ${_ship_staging}/documentation/licenses
          ${_ship_staging}/resources
  COMMAND ${CMAKE_COMMAND} -E copy ${_ship_recording} ${_ship_staging}/resources/ship_recording.csv
  COMMAND ${CMAKE_COMMAND} -E copy $<TARGET_FILE:${SHIP_MODEL_IDENTIFIER}>
          ${_ship_staging}/binaries/linux64/${SHIP_MODEL_IDENTIFIER}.so
  COMMAND ${CMAKE_COMMAND} -E copy ${PROJECT_SOURCE_DIR}/LICENSE ${_ship_staging}/documentation/licenses/Gimbal2Axis.txt
  ${_ship_win64_commands}
  COMMAND ${CMAKE_COMMAND} -E rm -f ${SHIP_MOTION_FMU}
  COMMAND ${CMAKE_COMMAND} -E tar cf ${SHIP_MOTION_FMU} --format=zip modelDescription.xml binaries documentation resources
  WORKING_DIRECTORY ${_ship_staging}
  DEPENDS ${SHIP_MODEL_IDENTIFIER} ${_ship_staging}/modelDescription.xml ${PROJECT_SOURCE_DIR}/LICENSE ${_ship_recording}
          ${_ship_win64_depends}
  COMMENT "Packaging Gimbal2Axis-ShipMotion.fmu")
add_custom_target(ship_motion_fmu ALL DEPENDS ${SHIP_MOTION_FMU})
