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

# generationDateAndTime: the rule of every model description of the project.
include(${CMAKE_CURRENT_LIST_DIR}/../fmu_src/common/generation_date.cmake)
set(GIMBAL_GENERATION_DATE ${GENERATION_DATE})

# The source FMU's <SourceFiles> (SOURCE_FILES: comma-separated names relative to sources/).
set(GIMBAL_SOURCE_FILES "")
string(REPLACE "," ";" _source_files "${SOURCE_FILES}")
foreach(_file IN LISTS _source_files)
  string(APPEND GIMBAL_SOURCE_FILES "      <File name=\"${_file}\"/>\n")
endforeach()
configure_file(${TEMPLATE} ${OUTPUT} @ONLY)
