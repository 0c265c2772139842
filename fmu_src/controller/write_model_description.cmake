# Build-time step: run the generator (GENERATOR) into OUTPUT with the version and the
# generationDateAndTime that the gimbal FMU's description carries (scripts/configure_model_description.cmake
# says why: SOURCE_DATE_EPOCH, else the last commit's time, else now).
if(NOT DEFINED ENV{SOURCE_DATE_EPOCH} AND GIT_EXECUTABLE)
  execute_process(COMMAND ${GIT_EXECUTABLE} log -1 --format=%ct WORKING_DIRECTORY ${SOURCE_DIR}
                  OUTPUT_VARIABLE _commit_time OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET RESULT_VARIABLE _git_result)
  if(_git_result EQUAL 0 AND _commit_time MATCHES "^[0-9]+$")
    set(ENV{SOURCE_DATE_EPOCH} ${_commit_time})
  endif()
endif()
string(TIMESTAMP _date "%Y-%m-%dT%H:%M:%SZ" UTC)
execute_process(COMMAND ${GENERATOR} ${OUTPUT} ${VERSION} ${_date} RESULT_VARIABLE _result)
if(NOT _result EQUAL 0)
  message(FATAL_ERROR "${GENERATOR} failed (${_result})")
endif()
