# Run femp on a bad scene: it must exit non-zero, print a message matching
# REGEX, and (unless WORK_ALLOWED) not start the computation (no banner, no
# output directory). Optional: ARGS, command-line arguments separated by '|'
# (replace PRM when PRM is empty); NPROC > 1 runs it with MPIEXEC on that
# many ranks (the test's TIMEOUT then catches a rank left waiting).
# COLLECTIVE: an error every rank meets during setup; it must end all ranks
# without MPI_Abort (no Open MPI banner), before the t = 0 output.
file(REMOVE_RECURSE ${WORKDIR})
file(MAKE_DIRECTORY ${WORKDIR})
set(args)
if(DEFINED ARGS AND NOT "${ARGS}" STREQUAL "")
  string(REPLACE "|" ";" args "${ARGS}")
endif()
if(NOT "${PRM}" STREQUAL "")
  list(APPEND args ${PRM})
endif()
set(cmd ${EXE} ${args})
if(DEFINED NPROC AND NPROC GREATER 1)
  set(cmd ${MPIEXEC} --allow-run-as-root --oversubscribe -np ${NPROC} ${cmd})
endif()
execute_process(
  COMMAND ${cmd}
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
if(NOT WORK_ALLOWED AND ("${out}" MATCHES "femp: [23]D scene" OR EXISTS ${WORKDIR}/output))
  message(FATAL_ERROR "femp started the computation before rejecting the input")
endif()
if(COLLECTIVE)
  if("${err}" MATCHES "MPI_ABORT|MPI_Abort")
    message(FATAL_ERROR "a collective error ended the run with MPI_Abort")
  endif()
  file(GLOB written ${WORKDIR}/output/*.vtu ${WORKDIR}/output/*.pvtu
       ${WORKDIR}/output/*.pvd)
  if(written)
    message(FATAL_ERROR "fields were written before the refusal: ${written}")
  endif()
endif()
