# The small Co-Simulation FMUs beside the gimbal's (fmu_src/ship_motion/, fmu_src/controller/), each
# as an FMI 2.0 and an FMI 3.0 FMU: one way to build their binaries and one to package them, so that
# they link, and their archives are laid out, alike. Two functions, not one: the binaries are built
# in the win64 cross build too, and the packaging waits for that build (fmu_src/win64.cmake).

# The files a small FMU's binary is compiled from, absolute: `target`'s sources and those of the
# static libraries it links, recursively (for sources/ and its build description).
function(small_fmu_source_files target out)
  set(_files "")
  get_target_property(_type ${target} TYPE)
  if(NOT _type STREQUAL "INTERFACE_LIBRARY")
    get_target_property(_sources ${target} SOURCES)
    get_target_property(_source_dir ${target} SOURCE_DIR)
    foreach(_source IN LISTS _sources)
      get_filename_component(_source ${_source} ABSOLUTE BASE_DIR ${_source_dir})
      if(_source MATCHES "\\.c$")
        list(APPEND _files ${_source})
      endif()
    endforeach()
  endif()
  get_target_property(_libraries ${target} LINK_LIBRARIES)
  foreach(_library IN LISTS _libraries)
    if(TARGET ${_library})
      small_fmu_source_files(${_library} _library_files)
      list(APPEND _files ${_library_files})
    endif()
  endforeach()
  list(REMOVE_DUPLICATES _files)
  set(${out} ${_files} PARENT_SCOPE)
endfunction()

# The link of a small FMU's binary, as the gimbal's (fmu_src/CMakeLists.txt says why each option):
# only the version's functions exported (`exports`: the version script), libgcc inside, on Linux the
# C runtime's libm and libc its only shared libraries.
function(link_small_fmu_binary target exports)
  # model_core/include: the status type the FMI layer shares with the core (gimbal/gimbal_status.h).
  target_include_directories(${target} PRIVATE ${FMI2_INCLUDE_DIR} ${PROJECT_BINARY_DIR}/generated
                             ${PROJECT_SOURCE_DIR}/fmu_src ${PROJECT_SOURCE_DIR}/fmu_src/common
                             ${PROJECT_SOURCE_DIR}/model_core/include)
  # No contraction into fused multiply-adds: the outputs are the bits the scene runner computes.
  target_compile_options(${target} PRIVATE -Wall -Wextra -ffp-contract=off)
  set_target_properties(${target} PROPERTIES PREFIX "" C_VISIBILITY_PRESET hidden)
  if(WIN32)
    target_link_options(${target} PRIVATE -static -Wl,--exclude-all-symbols)
  else()
    target_link_libraries(${target} PRIVATE m)
    set_target_properties(${target} PROPERTIES LINK_DEPENDS ${exports})
    target_link_options(${target} PRIVATE -static-libgcc -Wl,--version-script=${exports} -Wl,--exclude-libs,ALL)
    if(NOT GIMBAL_SANITIZE)
      target_link_options(${target} PRIVATE -Wl,--no-undefined)  # the sanitizer runtimes are preloaded instead
    endif()
  endif()
endfunction()

# add_small_cosimulation_fmu_binary(<model identifier>
#     SOURCES <the model file defining kFmuModel>... LIBRARIES <the model's libraries>...
#     VARIABLE_TABLE <file> GUID_HEADER <name>_guid.h.in GUID_VARIABLE <variable>)
# Two shared libraries named <model identifier> (no "lib" prefix), the model file over the FMI
# instance layer: target <model identifier>, the FMI 2.0 one (fmu_src/fmi_layer/fmi2_functions.c,
# only fmi2* exported), and target <model identifier>_fmi3 in fmi3/, the FMI 3.0 one
# (fmi3_functions.c, only fmi3* exported). Sets <variable> here and in the caller's scope to the
# FMU's GUID (the FMI 3.0 instantiation token too), a name-based UUID of the identifier, the version
# and the variable table (so that it changes with them), and configures GUID_HEADER with it into
# generated/.
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

  set(_layer ${PROJECT_SOURCE_DIR}/fmu_src/fmi_layer)
  set(_shared ${_layer}/fmu_model.c ${_layer}/fmi_instance.c ${_layer}/fmu_state.c)
  add_library(${identifier} SHARED ${ARG_SOURCES} ${_layer}/fmi2_functions.c ${_layer}/fmi2_face.c ${_shared})
  add_library(${identifier}_fmi3 SHARED ${ARG_SOURCES} ${_layer}/fmi3_functions.c ${_layer}/fmi3_face.c
              ${_layer}/fmi3_not_offered.c ${_shared})
  link_small_fmu_binary(${identifier} ${PROJECT_SOURCE_DIR}/fmu_src/exports.map)
  link_small_fmu_binary(${identifier}_fmi3 ${PROJECT_SOURCE_DIR}/fmu_src/exports_fmi3.map)
  # Its own directory: its file has the FMI 2.0 binary's name.
  set_target_properties(${identifier}_fmi3 PROPERTIES OUTPUT_NAME ${identifier}
                        LIBRARY_OUTPUT_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR}/fmi3
                        RUNTIME_OUTPUT_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR}/fmi3
                        ARCHIVE_OUTPUT_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR}/fmi3)
  foreach(_target ${identifier} ${identifier}_fmi3)
    target_link_libraries(${_target} PRIVATE ${ARG_LIBRARIES})
  endforeach()
endfunction()

# package_small_cosimulation_fmu(<name> FMU <file name> FMI_VERSION <2|3> MODEL_IDENTIFIER <identifier>
#     GUID <guid> TEMPLATE <modelDescription.xml.in> GENERATOR <executable> GENERATOR_SOURCES <files>...
#     [GENERATOR_LIBRARIES <libraries>...] LICENSE_AS <path in the FMU>
#     [WIN64_DLL <file> WIN64_DEPENDS <targets>...] [RESOURCES <files>...])
# build/<file name> (target <name>_fmu, FMI 3.0: <name>_fmu3), staged in build/<name>_staging (FMI 3.0:
# build/<name>_fmi3_staging): modelDescription.xml (the
# generator's fragments of the variable table in TEMPLATE, configure_model_description.cmake; the
# generator is given --fmi3 for FMI 3.0), the binary of add_small_cosimulation_fmu_binary of the
# version in binaries/linux64 (FMI 3.0: binaries/x86_64-linux) and, given one, the win64 DLL in
# binaries/win64 (x86_64-windows), sources/ (the files the binary is compiled from and the headers
# they include, listed in <SourceFiles>, FMI 3.0: in sources/buildDescription.xml), the project's
# licence at LICENSE_AS, the RESOURCES in resources/.
function(package_small_cosimulation_fmu name)
  cmake_parse_arguments(PARSE_ARGV 1 ARG "" "FMU;FMI_VERSION;MODEL_IDENTIFIER;GUID;TEMPLATE;GENERATOR;LICENSE_AS;WIN64_DLL"
                        "GENERATOR_SOURCES;GENERATOR_LIBRARIES;WIN64_DEPENDS;RESOURCES")
  set(_common ${PROJECT_SOURCE_DIR}/fmu_src/common)
  set(_fmu ${PROJECT_BINARY_DIR}/${ARG_FMU})
  if(ARG_FMI_VERSION STREQUAL "3")
    set(_target ${name}_fmu3)
    set(name ${name}_fmi3)
    set(_binary ${ARG_MODEL_IDENTIFIER}_fmi3)
    set(_generator_version --fmi3)
    set(_linux_folder binaries/x86_64-linux)
    set(_windows_folder binaries/x86_64-windows)
  else()
    set(_target ${name}_fmu)
    set(_binary ${ARG_MODEL_IDENTIFIER})
    set(_generator_version "")
    set(_linux_folder binaries/linux64)
    set(_windows_folder binaries/win64)
  endif()
  set(_staging ${PROJECT_BINARY_DIR}/${name}_staging)
  set(_fragments ${PROJECT_BINARY_DIR}/${name}_fragments)

  if(NOT TARGET ${ARG_GENERATOR})  # one generator writes both versions' fragments
    add_executable(${ARG_GENERATOR} ${ARG_GENERATOR_SOURCES} ${_common}/model_description_writer.c)
    target_include_directories(${ARG_GENERATOR} PRIVATE ${_common})
    target_compile_options(${ARG_GENERATOR} PRIVATE -Wall -Wextra)
    target_link_libraries(${ARG_GENERATOR} PRIVATE ${ARG_GENERATOR_LIBRARIES})
  endif()

  # sources/: the binary's own files as they are listed, with every header they include (without
  # SUNDIALS or Eigen, which the small FMUs do not use), collected as for the gimbal's FMU
  # (scripts/stage_fmu_sources.cmake); each file below the first include root that holds it, so that
  # sources/ itself is the one include directory a builder gives.
  small_fmu_source_files(${_binary} _source_files)
  get_target_property(_model_folder ${ARG_MODEL_IDENTIFIER} SOURCE_DIR)
  set(_roots ${_model_folder} ${PROJECT_SOURCE_DIR}/fmu_src ${PROJECT_BINARY_DIR}/generated
             ${PROJECT_SOURCE_DIR}/c_kernel/include ${PROJECT_SOURCE_DIR}/c_kernel/src
             ${PROJECT_SOURCE_DIR}/model_core/include)
  set(_source_names "")
  set(_source_entries "")
  foreach(_file IN LISTS _source_files)
    foreach(_root IN LISTS _roots)
      file(RELATIVE_PATH _name ${_root} ${_file})
      if(NOT _name MATCHES "^\\.\\.")
        break()
      endif()
    endforeach()
    list(APPEND _source_names ${_name})
    string(APPEND _source_entries "      <SourceFile name=\"${_name}\"/>\n")
  endforeach()
  string(JOIN "," _source_list ${_source_files})
  string(JOIN "," _root_list ${_roots})
  set(_sources_stamp ${PROJECT_BINARY_DIR}/${name}_sources.stamp)
  file(GLOB_RECURSE _source_inputs CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/fmu_src/*.c ${PROJECT_SOURCE_DIR}/fmu_src/*.h
       ${PROJECT_SOURCE_DIR}/c_kernel/src/*.c ${PROJECT_SOURCE_DIR}/c_kernel/include/*.h
       ${PROJECT_SOURCE_DIR}/model_core/include/gimbal/gimbal_status.h)
  add_custom_command(
    OUTPUT ${_sources_stamp}
    COMMAND ${CMAKE_COMMAND} -DCXX=${CMAKE_CXX_COMPILER} -DC=${CMAKE_C_COMPILER} -DSOURCES=${_source_list}
      -DROOTS=${_root_list} -DFMI2_INCLUDE_DIR=${FMI2_INCLUDE_DIR} -DEIGEN_DIR= -DOUTPUT=${_staging}/sources
      -DSTAMP=${_sources_stamp} -P ${PROJECT_SOURCE_DIR}/scripts/stage_fmu_sources.cmake
    DEPENDS ${_source_inputs} ${PROJECT_SOURCE_DIR}/scripts/stage_fmu_sources.cmake
    COMMENT "Collecting the sources/ of ${ARG_FMU}"
    VERBATIM)
  set(_source_description ${PROJECT_BINARY_DIR}/${name}_buildDescription.xml)
  if(ARG_FMI_VERSION STREQUAL "3")
    file(WRITE ${_source_description}
"<?xml version=\"1.0\" encoding=\"UTF-8\"?>
<fmiBuildDescription fmiVersion=\"3.0\">
  <BuildConfiguration modelIdentifier=\"${ARG_MODEL_IDENTIFIER}\" description=\"the .c files as C99 with -ffp-contract=off (no fused multiply-adds: the outputs keep the shipped binary's bits); the include path is sources/ itself\">
    <SourceFileSet language=\"C99\" compilerOptions=\"-ffp-contract=off\">
${_source_entries}      <IncludeDirectory name=\".\"/>
    </SourceFileSet>
  </BuildConfiguration>
</fmiBuildDescription>
")
    set(_copy_source_description COMMAND ${CMAKE_COMMAND} -E copy ${_source_description} sources/buildDescription.xml)
    set(_source_description_depends ${_source_description})
    set(SOURCE_FILES "")
  else()
    set(_copy_source_description "")
    set(_source_description_depends "")
    # <SourceFiles> inside <CoSimulation>, through the template's @SOURCE_FILES@.
    set(SOURCE_FILES "    <SourceFiles>\n")
    foreach(_name IN LISTS _source_names)
      string(APPEND SOURCE_FILES "      <File name=\"${_name}\"/>\n")
    endforeach()
    string(APPEND SOURCE_FILES "    </SourceFiles>\n")
  endif()

  # The template filled twice: with what is known now (the project's name, version, author,
  # copyright and licence, the identifier, the GUID, the source files), then at build time with the
  # generator's fragments and the date; their placeholders pass through the first filling as they are.
  foreach(_build_time_value IN ITEMS UNIT_DEFINITIONS MODEL_VARIABLES MODEL_STRUCTURE GENERATION_DATE)
    set(${_build_time_value} "@${_build_time_value}@")
  endforeach()
  set(MODEL_IDENTIFIER ${ARG_MODEL_IDENTIFIER})
  set(FMU_GUID ${ARG_GUID})
  configure_file(${ARG_TEMPLATE} ${_fragments}/modelDescription.xml.in @ONLY)
  add_custom_command(
    OUTPUT ${_staging}/modelDescription.xml
    COMMAND ${CMAKE_COMMAND} -E make_directory ${_fragments} ${_staging}
    COMMAND ${ARG_GENERATOR} ${_generator_version} ${_fragments}/units.xml ${_fragments}/variables.xml
            ${_fragments}/structure.xml
    COMMAND ${CMAKE_COMMAND} -DTEMPLATE=${_fragments}/modelDescription.xml.in -DOUTPUT=${_staging}/modelDescription.xml
            -DFRAGMENTS=${_fragments} -DSOURCE_DIR=${PROJECT_SOURCE_DIR} -DGIT_EXECUTABLE=${GIT_EXECUTABLE}
            -P ${_common}/configure_model_description.cmake
    DEPENDS ${ARG_GENERATOR} ${_fragments}/modelDescription.xml.in ${_common}/configure_model_description.cmake
            ${_common}/generation_date.cmake ${GIMBAL_HEAD_LOG}
    COMMENT "Configuring the modelDescription.xml of ${ARG_FMU}"
    VERBATIM)

  set(_optional_commands "")
  set(_folders modelDescription.xml binaries documentation sources)
  if(ARG_WIN64_DLL)
    list(APPEND _optional_commands
      COMMAND ${CMAKE_COMMAND} -E make_directory ${_windows_folder}
      COMMAND ${CMAKE_COMMAND} -E copy ${ARG_WIN64_DLL} ${_windows_folder}/${ARG_MODEL_IDENTIFIER}.dll)
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
    # Nothing an earlier build staged stays (a win64 binary of a build that had mingw-w64); sources/
    # is the stamp's.
    COMMAND ${CMAKE_COMMAND} -E rm -rf binaries documentation resources
    COMMAND ${CMAKE_COMMAND} -E make_directory ${_linux_folder} ${_license_folder}
    COMMAND ${CMAKE_COMMAND} -E copy $<TARGET_FILE:${_binary}> ${_linux_folder}/${ARG_MODEL_IDENTIFIER}.so
    COMMAND ${CMAKE_COMMAND} -E copy ${PROJECT_SOURCE_DIR}/LICENSE ${ARG_LICENSE_AS}
    ${_copy_source_description}
    ${_optional_commands}
    # reproducibly: the same staged files give the same bytes (scripts/package_fmu.py says why not tar)
    COMMAND ${Python3_EXECUTABLE} ${PROJECT_SOURCE_DIR}/scripts/package_fmu.py ${_fmu} ${_staging} ${_folders}
    WORKING_DIRECTORY ${_staging}
    DEPENDS ${_binary} ${PROJECT_SOURCE_DIR}/scripts/package_fmu.py ${_staging}/modelDescription.xml ${PROJECT_SOURCE_DIR}/LICENSE ${ARG_RESOURCES}
            ${ARG_WIN64_DLL} ${ARG_WIN64_DEPENDS} ${_sources_stamp} ${_source_description_depends}
    COMMENT "Packaging ${ARG_FMU}"
    VERBATIM)
  add_custom_target(${_target} ALL DEPENDS ${_fmu})
endfunction()
