# Build-time step: fill modelDescription.xml.in with the fragments the generator wrote.
file(READ ${FRAGMENTS}/units.xml GIMBAL_UNIT_DEFINITIONS)
file(READ ${FRAGMENTS}/types.xml GIMBAL_TYPE_DEFINITIONS)
file(READ ${FRAGMENTS}/variables.xml GIMBAL_MODEL_VARIABLES)
file(READ ${FRAGMENTS}/structure.xml GIMBAL_MODEL_STRUCTURE)
file(READ ${FRAGMENTS}/default_tolerance.txt GIMBAL_DEFAULT_TOLERANCE)
configure_file(${TEMPLATE} ${OUTPUT} @ONLY)
