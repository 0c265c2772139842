# The small FMI 2.0 Co-Simulation FMUs beside the gimbal's (fmu_src/ship_motion/, fmu_src/controller/):
# one way to build their binaries and one to package them, so that they link, and their archives
# are laid out, alike. Two functions, not one: the ship-motion binary is built in the win64 cross
# build too, and its packaging waits for that build (fmu_src/win64.cmake).

# add_small_cosimulation_fmu_binary(<model identifier>
#     SOURCES <the model file defining kSmallFmi2Model>... LIBRARIES <the model's libraries>...
#     VARIABLE_TABLE <file> GUID_HEADER <name>_guid.h.in GUID_VARIABLE <variable>)
# The shared library <model identifier> (no "lib" prefix): the model file behind the small FMUs' FMI
# 2.0 Co-Simulation face (fmu_src/fmi_layer/small_fmi2_cosim.c) on the FMI instance layer, linked
# as the gimbal's binary (fmu_src/CMakeLists.txt says why each option): only fmi2* exported, libgcc
# inside, on Linux the C runtime's libm and libc its only shared libraries. Sets <variable> here and
# in the caller's scope to the FMU's GUID, a name-based UUID of the identifier, the version and the
# variable table (so that it changes with them), and configures GUID_HEADER with it into generated/.
function(add_small_cosimulation_fmu_binary identifier)
  cmake_parse_arguments(PARSE_ARGV 1 ARG "" "VARIABLE_TABLE;GUID_HEADER;GUID_VARIABLE" "SOURCES;LIBRARIES")
  file(SHA1 ${ARG_VARIABLE_TABLE} _table_hash)
  set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${ARG_VARIABLE_TABLE})
  string(UUID _guid NAMESPACE 6ba7b811-9dad-11d1-80b4-00c04fd430c8
         NAME "${identifier}-${PROJECT_VERSION}-${_table_hash}" TYPE SHA1)
  set(${ARG_GUID_VARIABLE} "{${_guid}}")
  set(${ARG_GUID_VARIABLE} "{${_guid}}" PARENT_SCOPE)
  get_filename_component(_header ${ARG_GUID_HEADER} NAME_WLE)
  configure_file(${ARG_GUID_HEADER} ${PROJECT_BINARY_DIR}/generated/${_header} @ONLY)

  set(_common ${PROJECT_SOURCE_DIR}/fmu_src/common)
  set(_fmu_src ${PROJECT_SOURCE_DIR}/fmu_src)
  add_library(${identifier} SHARED ${ARG_SOURCES} ${_fmu_src}/fmi_layer/small_fmi2_cosim.c
              ${_fmu_src}/fmi_layer/fmi_instance.c ${_fmu_src}/fmi_layer/fmi2_face.c ${_fmu_src}/fmu_state.c)
  target_include_directories(${identifier} PRIVATE ${FMI2_INCLUDE_DIR} ${PROJECT_BINARY_DIR}/generated
                             ${PROJECT_SOURCE_DIR}/fmu_src ${_common})
  # No contraction into fused multiply-adds: the outputs are the bits the scene runner computes.
  target_compile_options(${identifier} PRIVATE -Wall -Wextra -ffp-contract=off)
  target_link_libraries(${identifier} PRIVATE ${ARG_LIBRARIES})
  set_target_properties(${identifier} PROPERTIES PREFIX "" C_VISIBILITY_PRESET hidden)
  if(WIN32)
    target_link_options(${identifier} PRIVATE -static -Wl,--exclude-all-symbols)
  else()
    target_link_libraries(${identifier} PRIVATE m)
    set_target_properties(${identifier} PROPERTIES LINK_DEPENDS ${PROJECT_SOURCE_DIR}/fmu_src/exports.map)
    target_link_options(${identifier} PRIVATE -static-libgcc
                        -Wl,--version-script=${PROJECT_SOURCE_DIR}/fmu_src/exports.map -Wl,--exclude-libs,ALL)
    if(NOT GIMBAL_SANITIZE)
      target_link_options(${identifier} PRIVATE -Wl,--no-undefined)  # the sanitizer runtimes are preloaded instead
    endif()
  endif()
endfunction()

# package_small_cosimulation_fmu(<name> FMU <file name> MODEL_IDENTIFIER <identifier> GUID <guid>
#     TEMPLATE <modelDescription.xml.in> GENERATOR <executable> GENERATOR_SOURCES <files>...
#     [GENERATOR_LIBRARIES <libraries>...] LICENSE_AS <path in the FMU>
#     [WIN64_DLL <file> WIN64_DEPENDS <targets>...] [RESOURCES <files>...])
# build/<file name> (target <name>_fmu), staged in build/<name>_staging: modelDescription.xml (the
# generator's fragments of the variable table in TEMPLATE, configure_model_description.cmake), the
# binary of add_small_cosimulation_fmu_binary in binaries/linux64 and, given one, the win64 DLL in
# binaries/win64, the project's licence at LICENSE_AS, the RESOURCES in resources/.
function(package_small_cosimulation_fmu name)
  cmake_parse_arguments(PARSE_ARGV 1 ARG "" "FMU;MODEL_IDENTIFIER;GUID;TEMPLATE;GENERATOR;LICENSE_AS;WIN64_DLL"
                        "GENERATOR_SOURCES;GENERATOR_LIBRARIES;WIN64_DEPENDS;RESOURCES")
  set(_common ${PROJECT_SOURCE_DIR}/fmu_src/common)
  set(_staging ${PROJECT_BINARY_DIR}/${name}_staging)
  set(_fragments ${PROJECT_BINARY_DIR}/${name}_fragments)
  set(_fmu ${PROJECT_BINARY_DIR}/${ARG_FMU})

  add_executable(${ARG_GENERATOR} ${ARG_GENERATOR_SOURCES} ${_common}/model_description_writer.c)
  target_include_directories(${ARG_GENERATOR} PRIVATE ${_common})
  target_compile_options(${ARG_GENERATOR} PRIVATE -Wall -Wextra)
  target_link_libraries(${ARG_GENERATOR} PRIVATE ${ARG_GENERATOR_LIBRARIES})
  # The template filled twice: with what is known now (the project's name, version, author,
  # copyright and licence, the identifier, the GUID), then at build time with the generator's
  # fragments and the date; their placeholders pass through the first filling as they are.
  foreach(_build_time_value IN ITEMS UNIT_DEFINITIONS MODEL_VARIABLES MODEL_STRUCTURE GENERATION_DATE)
    set(${_build_time_value} "@${_build_time_value}@")
  endforeach()
  set(MODEL_IDENTIFIER ${ARG_MODEL_IDENTIFIER})
  set(FMU_GUID ${ARG_GUID})
  configure_file(${ARG_TEMPLATE} ${_fragments}/modelDescription.xml.in @ONLY)
  add_custom_command(
    OUTPUT ${_staging}/modelDescription.xml
    COMMAND ${CMAKE_COMMAND} -E make_directory ${_fragments} ${_staging}
    COMMAND ${ARG_GENERATOR} ${_fragments}/units.xml ${_fragments}/variables.xml ${_fragments}/structure.xml
    COMMAND ${CMAKE_COMMAND} -DTEMPLATE=${_fragments}/modelDescription.xml.in -DOUTPUT=${_staging}/modelDescription.xml
            -DFRAGMENTS=${_fragments} -DSOURCE_DIR=${PROJECT_SOURCE_DIR} -DGIT_EXECUTABLE=${GIT_EXECUTABLE}
            -P ${_common}/configure_model_description.cmake
    DEPENDS ${ARG_GENERATOR} ${_fragments}/modelDescription.xml.in ${_common}/configure_model_description.cmake
            ${_common}/generation_date.cmake ${GIMBAL_HEAD_LOG}
    COMMENT "Configuring the modelDescription.xml of ${ARG_FMU}"
    VERBATIM)

  set(_optional_commands "")
  set(_folders modelDescription.xml binaries documentation)
  if(ARG_WIN64_DLL)
    list(APPEND _optional_commands
      COMMAND ${CMAKE_COMMAND} -E make_directory binaries/win64
      COMMAND ${CMAKE_COMMAND} -E copy ${ARG_WIN64_DLL} binaries/win64/${ARG_MODEL_IDENTIFIER}.dll)
  endif()
  if(ARG_RESOURCES)
    list(APPEND _optional_commands COMMAND ${CMAKE_COMMAND} -E make_directory resources)
    foreach(_resource IN LISTS ARG_RESOURCES)
      get_filename_component(_resource_name ${_resource} NAME)
      list(APPEND _optional_commands COMMAND ${CMAKE_COMMAND} -E copy ${_resource} resources/${_resource_name})
    endforeach()
    list(APPEND _folders resources)
  endif()
  get_filename_component(_license_folder ${ARG_LICENSE_AS} DIRECTORY)
  add_custom_command(
    OUTPUT ${_fmu}
    # Nothing an earlier build staged stays (a win64 binary of a build that had mingw-w64).
    COMMAND ${CMAKE_COMMAND} -E rm -rf binaries documentation resources
    COMMAND ${CMAKE_COMMAND} -E make_directory binaries/linux64 ${_license_folder}
    COMMAND ${CMAKE_COMMAND} -E copy $<TARGET_FILE:${ARG_MODEL_IDENTIFIER}> binaries/linux64/${ARG_MODEL_IDENTIFIER}.so
    COMMAND ${CMAKE_COMMAND} -E copy ${PROJECT_SOURCE_DIR}/LICENSE ${ARG_LICENSE_AS}
    ${_optional_commands}
    COMMAND ${CMAKE_COMMAND} -E rm -f ${_fmu}
    COMMAND ${CMAKE_COMMAND} -E tar cf ${_fmu} --format=zip ${_folders}
    WORKING_DIRECTORY ${_staging}
    DEPENDS ${ARG_MODEL_IDENTIFIER} ${_staging}/modelDescription.xml ${PROJECT_SOURCE_DIR}/LICENSE ${ARG_RESOURCES}
            ${ARG_WIN64_DLL} ${ARG_WIN64_DEPENDS}
    COMMENT "Packaging ${ARG_FMU}"
    VERBATIM)
  add_custom_target(${name}_fmu ALL DEPENDS ${_fmu})
endfunction()
