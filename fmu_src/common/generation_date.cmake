# generationDateAndTime of every model description of the project (included by the build-time
# scripts scripts/configure_model_description.cmake and configure_model_description.cmake here, with
# SOURCE_DIR and GIT_EXECUTABLE defined): sets GENERATION_DATE, in UTC. Reproducible: the same
# sources give the same modelDescription.xml.
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
string(TIMESTAMP GENERATION_DATE "%Y-%m-%dT%H:%M:%SZ" UTC)
