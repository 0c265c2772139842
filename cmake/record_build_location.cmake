# Whether configuring this build writes gimbal2axis/build_locations.json, the file through which the
# package's `gimbal2axis` command finds the FMU and the probe library (gimbal2axis/locations.py).
#
# The file names one build: the one the package was set up with (scripts/setup.sh configures build/).
# A second build folder (another configuration, a benchmark build, a helper's build) must not take the
# package over silently, so GIMBAL_RECORD_BUILD_IN_PACKAGE is
#   AUTO (default) write it when it is absent, when it already names this build, or when the build it
#        names is gone (its folder has no CMakeCache.txt); otherwise leave it and say so;
#   ON   write it: this build becomes the package's;
#   OFF  never write it.
# Kept apart from CMakeLists.txt so that tests/layout/test_build_locations.py can run the decision in script
# mode (cmake -P) on files of its own.

# Sets <out_var> to TRUE or FALSE, and <reason_var> to one sentence saying why when it is FALSE.
function(gimbal_should_record_build out_var reason_var locations_file binary_dir mode)
  string(TOUPPER "${mode}" mode)
  if(mode STREQUAL "OFF" OR mode STREQUAL "FALSE" OR mode STREQUAL "0" OR mode STREQUAL "NO")
    set(${out_var} FALSE PARENT_SCOPE)
    set(${reason_var} "GIMBAL_RECORD_BUILD_IN_PACKAGE is OFF" PARENT_SCOPE)
    return()
  endif()
  if(mode STREQUAL "ON" OR mode STREQUAL "TRUE" OR mode STREQUAL "1" OR mode STREQUAL "YES")
    set(${out_var} TRUE PARENT_SCOPE)
    return()
  endif()
  if(NOT mode STREQUAL "AUTO")
    message(FATAL_ERROR "GIMBAL_RECORD_BUILD_IN_PACKAGE is '${mode}': AUTO, ON or OFF")
  endif()
  if(NOT EXISTS "${locations_file}")
    set(${out_var} TRUE PARENT_SCOPE)
    return()
  endif()
  file(READ "${locations_file}" recorded)
  # The file is ours (written below): "fmu": "<build>/<model>.fmu"
  if(NOT recorded MATCHES "\"fmu\"[ \t\r\n]*:[ \t\r\n]*\"([^\"]*)\"")
    set(${out_var} TRUE PARENT_SCOPE)   # unreadable: replace it rather than leave the package without a build
    return()
  endif()
  get_filename_component(recorded_dir "${CMAKE_MATCH_1}" DIRECTORY)
  get_filename_component(recorded_dir "${recorded_dir}" REALPATH)
  get_filename_component(this_dir "${binary_dir}" REALPATH)
  if(recorded_dir STREQUAL this_dir OR NOT EXISTS "${recorded_dir}/CMakeCache.txt")
    set(${out_var} TRUE PARENT_SCOPE)
    return()
  endif()
  set(${out_var} FALSE PARENT_SCOPE)
  set(${reason_var} "it names the build in ${recorded_dir}, which the package keeps using; configure with \
-DGIMBAL_RECORD_BUILD_IN_PACKAGE=ON to make this build the package's, or point GIMBAL2AXIS_FMU and \
GIMBAL2AXIS_PROBE_LIBRARY at its files" PARENT_SCOPE)
endfunction()

# Script mode, for the test: cmake -DLOCATIONS_FILE=... -DBINARY_DIR=... -DMODE=... -P this file
if(CMAKE_SCRIPT_MODE_FILE STREQUAL CMAKE_CURRENT_LIST_FILE)
  gimbal_should_record_build(record reason "${LOCATIONS_FILE}" "${BINARY_DIR}" "${MODE}")
  if(record)
    message("record")
  else()
    message("keep: ${reason}")
  endif()
endif()
