# Build-time step: fill modelDescription.xml.in with the fragments the generator wrote.
file(READ ${FRAGMENTS}/units.xml GIMBAL_UNIT_DEFINITIONS)
file(READ ${FRAGMENTS}/types.xml GIMBAL_TYPE_DEFINITIONS)
file(READ ${FRAGMENTS}/variables.xml GIMBAL_MODEL_VARIABLES)
file(READ ${FRAGMENTS}/structure.xml GIMBAL_MODEL_STRUCTURE)
file(READ ${FRAGMENTS}/default_tolerance.txt GIMBAL_DEFAULT_TOLERANCE)
# numberOfEventIndicators: the core's count (gimbal_c_api.h), the one place it is written.
file(STRINGS ${SOURCE_DIR}/model_core/include/gimbal/gimbal_c_api.h _indicators REGEX "^#define GIMBAL_EVENT_INDICATORS ")
string(REGEX REPLACE "^#define GIMBAL_EVENT_INDICATORS ([0-9]+).*" "\\1" GIMBAL_EVENT_INDICATORS "${_indicators}")
if(NOT GIMBAL_EVENT_INDICATORS MATCHES "^[0-9]+$")
  message(FATAL_ERROR "GIMBAL_EVENT_INDICATORS not found in gimbal_c_api.h")
endif()

# generationDateAndTime, in UTC. Reproducible: the same sources give the same modelDescription.xml.
# - SOURCE_DATE_EPOCH when set (the reproducible-builds convention; string(TIMESTAMP) honours it);
# - else the time of the last commit: it says which sources the FMU was made from, and rebuilding
#   the same commit anywhere gives the same bytes (the build time would differ at every build);
#   a build from a modified tree carries the time of the commit it started from;
# - else (no git, e.g. a source archive) the time of this build.
if(NOT DEFINED ENV{SOURCE_DATE_EPOCH} AND GIT_EXECUTABLE)
  execute_process(COMMAND ${GIT_EXECUTABLE} log -1 --format=%ct WORKING_DIRECTORY ${SOURCE_DIR}
                  OUTPUT_VARIABLE _commit_time OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET
                  RESULT_VARIABLE _git_result)
  if(_git_result EQUAL 0 AND _commit_time MATCHES "^[0-9]+$")
    set(ENV{SOURCE_DATE_EPOCH} ${_commit_time})
  endif()
endif()
string(TIMESTAMP GIMBAL_GENERATION_DATE "%Y-%m-%dT%H:%M:%SZ" UTC)

# The source FMU's <SourceFiles> (SOURCE_FILES: comma-separated names relative to sources/).
set(GIMBAL_SOURCE_FILES "")
string(REPLACE "," ";" _source_files "${SOURCE_FILES}")
foreach(_file IN LISTS _source_files)
  string(APPEND GIMBAL_SOURCE_FILES "      <File name=\"${_file}\"/>\n")
endforeach()
configure_file(${TEMPLATE} ${OUTPUT} @ONLY)
