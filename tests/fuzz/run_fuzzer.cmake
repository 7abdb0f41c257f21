# CTest's fuzz run: FUZZER over a fresh copy of its seed corpus (new inputs go to WORK, never
# into the source tree) for RUNS inputs. Fails on any finding (libFuzzer's exit status), and
# unless libFuzzer reports the runs done: a target that did not fuzz cannot pass.
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK}/corpus ${WORK}/artifacts)
execute_process(
  COMMAND ${FUZZER} -runs=${RUNS} -rss_limit_mb=2048 -malloc_limit_mb=1024 -timeout=20
          -print_final_stats=1 -artifact_prefix=${WORK}/artifacts/ ${WORK}/corpus ${SEEDS}
  RESULT_VARIABLE status
  OUTPUT_VARIABLE output
  ERROR_VARIABLE output)
message("${output}")
if(NOT status EQUAL 0)
  message(FATAL_ERROR "${FUZZER}: exit status ${status} (a finding: see above and ${WORK}/artifacts)")
endif()
if(NOT output MATCHES "Done ${RUNS} runs")
  message(FATAL_ERROR "${FUZZER}: libFuzzer did not report ${RUNS} runs done")
endif()
string(REGEX MATCH "stat::number_of_executed_units: *[0-9]+" execs "${output}")
message("${FUZZER}: ${execs}")
