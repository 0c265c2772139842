# Build-time step: fill modelDescription.xml.in with the fragments the generator wrote.
file(READ ${FRAGMENTS}/units.xml GIMBAL_UNIT_DEFINITIONS)
file(READ ${FRAGMENTS}/variables.xml GIMBAL_MODEL_VARIABLES)
file(READ ${FRAGMENTS}/structure.xml GIMBAL_MODEL_STRUCTURE)
# The source FMU's <SourceFiles> (SOURCE_FILES: comma-separated names relative to sources/).
set(GIMBAL_SOURCE_FILES "")
string(REPLACE "," ";" _source_files "${SOURCE_FILES}")
foreach(_file IN LISTS _source_files)
  string(APPEND GIMBAL_SOURCE_FILES "      <File name=\"${_file}\"/>\n")
endforeach()
configure_file(${TEMPLATE} ${OUTPUT} @ONLY)
