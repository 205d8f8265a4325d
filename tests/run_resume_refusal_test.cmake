# Run femp on PRM (a scene that writes checkpoints; FIRST_ARGS, optional,
# separated by '|', go before it): it must succeed and leave a checkpoint
# index in output/checkpoint. Then resume it with ARGS
# (command-line arguments separated by '|', e.g. a --set that changes the
# scene): femp must exit non-zero with a message matching REGEX before any
# work (no banner).
file(REMOVE_RECURSE ${WORKDIR})
file(MAKE_DIRECTORY ${WORKDIR})
string(REPLACE "|" ";" first_args "${FIRST_ARGS}")
execute_process(
  COMMAND ${EXE} ${first_args} ${PRM}
  WORKING_DIRECTORY ${WORKDIR}
  OUTPUT_VARIABLE out
  ERROR_VARIABLE err
  RESULT_VARIABLE rc)
if(NOT rc EQUAL 0 OR NOT EXISTS ${WORKDIR}/output/checkpoint/index)
  message(FATAL_ERROR "the run that writes checkpoints failed (exit ${rc}) "
                      "or wrote none:\n${out}\n${err}")
endif()
string(REPLACE "|" ";" args "${ARGS}")
execute_process(
  COMMAND ${EXE} --resume output/checkpoint ${args} ${PRM}
  WORKING_DIRECTORY ${WORKDIR}
  OUTPUT_VARIABLE out
  ERROR_VARIABLE err
  RESULT_VARIABLE rc)
message("exit ${rc}\nstdout: ${out}\nstderr: ${err}")
if(rc EQUAL 0)
  message(FATAL_ERROR "femp resumed a checkpoint of another scene")
endif()
if(NOT "${err}" MATCHES "${REGEX}")
  message(FATAL_ERROR "the error message does not match '${REGEX}'")
endif()
if("${out}" MATCHES "femp: [23]D scene")
  message(FATAL_ERROR "femp started the computation before rejecting the checkpoint")
endif()
