# Run one femp test program (on NPROC MPI ranks) in WORKDIR and compare its
# standard output with EXPECTED by numdiff.
file(REMOVE_RECURSE ${WORKDIR})
file(MAKE_DIRECTORY ${WORKDIR})
separate_arguments(flags UNIX_COMMAND "${MPIFLAGS}")
string(REPLACE "|" ";" args "${ARGS}")
execute_process(
  COMMAND ${MPIEXEC} ${flags} -np ${NPROC} ${EXE} ${args}
  WORKING_DIRECTORY ${WORKDIR}
  OUTPUT_FILE ${WORKDIR}/test_stdout
  ERROR_FILE ${WORKDIR}/test_stderr
  RESULT_VARIABLE rc)
file(READ ${WORKDIR}/test_stdout out)
message("${out}")
if(NOT rc EQUAL 0)
  file(READ ${WORKDIR}/test_stderr err)
  message(FATAL_ERROR "test program failed (exit ${rc}):\n${err}")
endif()
execute_process(
  COMMAND ${NUMDIFF} -q -a 1e-6 -r 1e-5 -s " \t\n=,:;<>[](){}^" ${EXPECTED} ${WORKDIR}/test_stdout
  RESULT_VARIABLE diff_rc)
if(NOT diff_rc EQUAL 0)
  execute_process(COMMAND ${NUMDIFF} -a 1e-6 -r 1e-5 -s " \t\n=,:;<>[](){}^" ${EXPECTED} ${WORKDIR}/test_stdout)
  message(FATAL_ERROR "output differs from ${EXPECTED}")
endif()
