# Build-time step of a small Co-Simulation FMU (small_cosimulation_fmu.cmake): fill its
# modelDescription.xml.in (TEMPLATE, the project's values already in) with the fragments its
# generator wrote into FRAGMENTS and the generation date, into OUTPUT.
file(READ ${FRAGMENTS}/units.xml UNIT_DEFINITIONS)
file(READ ${FRAGMENTS}/variables.xml MODEL_VARIABLES)
file(READ ${FRAGMENTS}/structure.xml MODEL_STRUCTURE)
include(${CMAKE_CURRENT_LIST_DIR}/generation_date.cmake)
configure_file(${TEMPLATE} ${OUTPUT} @ONLY)
