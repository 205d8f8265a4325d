cmake_minimum_required(VERSION 3.13) # literal @WORKDIR@ below (policy CMP0053)
# Run femp on tests/render_tiny.prm (NPROC ranks) in WORKDIR, once with VTU
# and once with HDF5 output, then each command of CHECKS (separated by '|',
# '@DIR@' replaced by the output directories 'vtu hdf5'): the render test
# runs contrib/render.py by pvbatch on both and checks that every picture
# shows the track; the femp_post test reads both with contrib/femp_post.py.
file(REMOVE_RECURSE ${WORKDIR})
file(MAKE_DIRECTORY ${WORKDIR})
separate_arguments(flags UNIX_COMMAND "${MPIFLAGS}")
foreach(format vtu hdf5)
  execute_process(
    COMMAND ${MPIEXEC} ${flags} -np ${NPROC} ${FEMP} ${PRM}
      --set "Output/Directory=${WORKDIR}/${format}"
      --set "Output/Format=${format}"
    WORKING_DIRECTORY ${WORKDIR}
    OUTPUT_FILE ${WORKDIR}/femp_${format}.log
    ERROR_FILE ${WORKDIR}/femp_${format}.err
    RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    file(READ ${WORKDIR}/femp_${format}.err err)
    message(FATAL_ERROR "femp failed on ${PRM} (${format}, exit ${rc}):\n${err}")
  endif()
endforeach()
string(REPLACE "|" ";" checks "${CHECKS}")
foreach(check ${checks})
  string(REPLACE "@WORKDIR@" "${WORKDIR}" check "${check}")
  separate_arguments(cmd UNIX_COMMAND "${check}")
  execute_process(COMMAND ${cmd}
    WORKING_DIRECTORY ${WORKDIR}
    OUTPUT_VARIABLE out ERROR_VARIABLE err RESULT_VARIABLE rc)
  message("${out}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "'${check}' failed (exit ${rc}):\n${err}")
  endif()
endforeach()
