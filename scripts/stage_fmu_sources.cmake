# Build-time step: the source FMU's sources/ directory (FMI 2.0, section 2.3), the files listed in
# modelDescription.xml's <SourceFiles> and every header they include, found by the compiler itself
# (-M) rather than by a list that could go stale. Each file lands at its path relative to the include
# root it was found under, so the one include path a builder gives, sources/ itself, finds them all:
#   model_core/src/<layer>/*, fmu_src/*, gimbal_guid.h (generated) -> sources/<layer>/, sources/
#   model_core/include/gimbal/[<layer>/]*                        -> sources/gimbal/[<layer>/]
#   Eigen's headers (from the system's Eigen, MPL2)           -> sources/Eigen/
# The FMI headers are not copied (the standard leaves them to the importer), nor system headers.
# Eigen's CPU back ends (Eigen/src/Core/arch) are copied whole: -M sees only this machine's, and
# the sources are meant to compile on others.
#
# Arguments (-D): CXX, C (compilers), SOURCES (comma-separated absolute paths), ROOTS
# (comma-separated include roots, searched in order), FMI2_INCLUDE_DIR, EIGEN_DIR (empty: none), OUTPUT (the
# sources/ directory, recreated), STAMP.
string(REPLACE "," ";" _sources "${SOURCES}")
string(REPLACE "," ";" _roots "${ROOTS}")
file(REMOVE_RECURSE ${OUTPUT})
file(MAKE_DIRECTORY ${OUTPUT})

set(_flags -DGIMBAL_WITH_SUNDIALS=0 -I${FMI2_INCLUDE_DIR})
foreach(_root IN LISTS _roots)
  list(APPEND _flags -I${_root})
endforeach()

set(_files "")
foreach(_source IN LISTS _sources)
  if(_source MATCHES "\\.c$")
    set(_compiler ${C} -std=c99)
  else()
    set(_compiler ${CXX} -std=c++17)
  endif()
  execute_process(COMMAND ${_compiler} -M ${_flags} ${_source}
                  OUTPUT_VARIABLE _rule ERROR_VARIABLE _error RESULT_VARIABLE _result)
  if(NOT _result EQUAL 0)
    message(FATAL_ERROR "stage_fmu_sources: cannot find the headers of ${_source}:\n${_error}")
  endif()
  string(REPLACE "\\\n" " " _rule "${_rule}")
  string(REGEX REPLACE "^[^:]*:" "" _rule "${_rule}")
  string(REGEX REPLACE "[ \t\r\n]+" ";" _rule "${_rule}")
  list(APPEND _files ${_rule})
endforeach()
list(REMOVE_ITEM _files "")
list(REMOVE_DUPLICATES _files)

get_filename_component(_fmi2_dir ${FMI2_INCLUDE_DIR} ABSOLUTE)
foreach(_file IN LISTS _files)
  get_filename_component(_file ${_file} ABSOLUTE)
  if(_file MATCHES "^${_fmi2_dir}/")
    continue()
  endif()
  set(_relative "")
  foreach(_root IN LISTS _roots)
    get_filename_component(_root ${_root} ABSOLUTE)
    string(LENGTH "${_root}/" _length)
    string(SUBSTRING "${_file}" 0 ${_length} _head)
    if(_head STREQUAL "${_root}/")
      string(SUBSTRING "${_file}" ${_length} -1 _relative)
      break()
    endif()
  endforeach()
  if(_relative STREQUAL "")
    continue()  # a system header
  endif()
  get_filename_component(_directory ${OUTPUT}/${_relative} DIRECTORY)
  file(COPY ${_file} DESTINATION ${_directory})
endforeach()

# Eigen's back ends and licence, for a sources/ that includes Eigen (not the small FMUs': EIGEN_DIR empty).
if(EIGEN_DIR)
  file(GLOB _arch LIST_DIRECTORIES true ${EIGEN_DIR}/Eigen/src/Core/arch/*)
  foreach(_backend IN LISTS _arch)
    get_filename_component(_name ${_backend} NAME)
    if(NOT _name MATCHES "^(CUDA|GPU|HIP|SYCL)$")  # reached only by device compilers
      file(COPY ${_backend} DESTINATION ${OUTPUT}/Eigen/src/Core/arch)
    endif()
  endforeach()
  # Eigen's licence next to it (each of its headers points to the MPL 2.0).
  if(EXISTS /usr/share/common-licenses/MPL-2.0)
    configure_file(/usr/share/common-licenses/MPL-2.0 ${OUTPUT}/Eigen/COPYING.MPL2 COPYONLY)
  endif()
endif()
file(TOUCH ${STAMP})
