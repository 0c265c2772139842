# Build-time step: fill modelDescription.xml.in with the fragments the generator wrote.
file(READ ${FRAGMENTS}/units.xml SHIP_UNIT_DEFINITIONS)
file(READ ${FRAGMENTS}/variables.xml SHIP_MODEL_VARIABLES)
file(READ ${FRAGMENTS}/structure.xml SHIP_MODEL_STRUCTURE)
# generationDateAndTime as the gimbal's (scripts/configure_model_description.cmake says why): the
# SOURCE_DATE_EPOCH if set, else the time of the last commit, else now.
if(NOT DEFINED ENV{SOURCE_DATE_EPOCH} AND GIT_EXECUTABLE)
  execute_process(COMMAND ${GIT_EXECUTABLE} log -1 --format=%ct WORKING_DIRECTORY ${SOURCE_DIR}
                  OUTPUT_VARIABLE _commit_time OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET RESULT_VARIABLE _git_result)
  if(_git_result EQUAL 0 AND _commit_time MATCHES "^[0-9]+$")
    set(ENV{SOURCE_DATE_EPOCH} ${_commit_time})
  endif()
endif()
string(TIMESTAMP GENERATION_DATE "%Y-%m-%dT%H:%M:%SZ" UTC)
configure_file(${TEMPLATE} ${OUTPUT} @ONLY)
