# Build-time step: fill modelDescription.xml.in with the fragments the generator wrote.
file(READ ${FRAGMENTS}/units.xml GIMBAL_UNIT_DEFINITIONS)
file(READ ${FRAGMENTS}/types.xml GIMBAL_TYPE_DEFINITIONS)
file(READ ${FRAGMENTS}/variables.xml GIMBAL_MODEL_VARIABLES)
file(READ ${FRAGMENTS}/structure.xml GIMBAL_MODEL_STRUCTURE)
file(READ ${FRAGMENTS}/default_tolerance.txt GIMBAL_DEFAULT_TOLERANCE)
# numberOfEventIndicators and the mode outputs: the generator's, from the switching elements' one
# declaration (model_core/include/gimbal/switching_elements.def).
file(READ ${FRAGMENTS}/event_indicators.txt GIMBAL_EVENT_INDICATORS)
file(READ ${FRAGMENTS}/vendor_annotations.xml GIMBAL_VENDOR_ANNOTATIONS)
if(NOT GIMBAL_EVENT_INDICATORS MATCHES "^[0-9]+$")
  message(FATAL_ERROR "event_indicators.txt holds no count: '${GIMBAL_EVENT_INDICATORS}'")
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
