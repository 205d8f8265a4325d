# Run femp on a bad scene: it must exit non-zero, print a message matching
# REGEX, and not start the computation (no banner, no output directory).
file(REMOVE_RECURSE ${WORKDIR})
file(MAKE_DIRECTORY ${WORKDIR})
execute_process(
  COMMAND ${EXE} ${PRM}
  WORKING_DIRECTORY ${WORKDIR}
  OUTPUT_VARIABLE out
  ERROR_VARIABLE err
  RESULT_VARIABLE rc)
message("exit ${rc}\nstdout: ${out}\nstderr: ${err}")
if(rc EQUAL 0)
  message(FATAL_ERROR "femp accepted a bad scene")
endif()
if(NOT "${err}" MATCHES "${REGEX}")
  message(FATAL_ERROR "the error message does not match '${REGEX}'")
endif()
if("${out}" MATCHES "femp: [23]D scene" OR EXISTS ${WORKDIR}/output)
  message(FATAL_ERROR "femp started the computation before rejecting the input")
endif()
