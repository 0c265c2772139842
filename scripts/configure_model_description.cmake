# Build-time step: fill modelDescription.xml.in with the fragments the generator wrote.
file(READ ${FRAGMENTS}/units.xml GIMBAL_UNIT_DEFINITIONS)
file(READ ${FRAGMENTS}/variables.xml GIMBAL_MODEL_VARIABLES)
file(READ ${FRAGMENTS}/structure.xml GIMBAL_MODEL_STRUCTURE)
configure_file(${TEMPLATE} ${OUTPUT} @ONLY)
