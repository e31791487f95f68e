# fuzz_run test: a libFuzzer binary tries RUNS inputs from seed SEED, starting from the shipped
# CORPUS alone. WORK (the scratch corpus it adds to) is emptied first, so inputs found by an
# earlier run do not carry over.
foreach(var FUZZER WORK CORPUS SEED RUNS)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "fuzz_run.cmake: -D${var}= is required")
  endif()
endforeach()
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")
execute_process(
  COMMAND ${CMAKE_COMMAND} -E env ASAN_OPTIONS=detect_leaks=1
          "${FUZZER}" -seed=${SEED} -runs=${RUNS} -print_final_stats=1 -artifact_prefix=${WORK}.
          "${WORK}" "${CORPUS}"
  RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "fuzz_run: ${FUZZER} -seed=${SEED} -runs=${RUNS} exited with ${rc}; "
                      "the failing input is ${WORK}.crash-* (replay it with the target's _replay program)")
endif()
