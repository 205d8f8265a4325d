# The documented parameter listing doc/parameters.prm must be exactly what
# `femp --print-parameters` prints.
execute_process(COMMAND ${EXE} --print-parameters
  OUTPUT_VARIABLE listing RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "femp --print-parameters failed (exit ${rc})")
endif()
file(READ ${DOC} documented)
if(NOT "${listing}" STREQUAL "${documented}")
  file(WRITE ${WORKDIR}/parameters.prm "${listing}")
  message(FATAL_ERROR "doc/parameters.prm differs from `femp --print-parameters` "
    "(the current listing is in ${WORKDIR}/parameters.prm). Regenerate it "
    "from the source directory with:\n  build/femp --print-parameters > doc/parameters.prm")
endif()
