# Runs one fuzz target for SECONDS on a scratch copy of its seed corpus (so that what it
# finds never lands in the source tree), then reports its last status line. The seed is
# fixed (SEED, default 1): the suite replays the committed corpus and then the same
# mutations each run, so its verdict does not depend on luck; longer runs with other
# seeds happen outside it, and what they find joins the corpus with a regression test.
#   cmake -DTARGET=... -DCORPUS=... -DSCRATCH=... -DSECONDS=20 [-DDICT=...]
#         -P run_fuzz_target.cmake
cmake_minimum_required(VERSION 3.20)
file(REMOVE_RECURSE "${SCRATCH}")
file(MAKE_DIRECTORY "${SCRATCH}/corpus" "${SCRATCH}/artifacts")
file(COPY "${CORPUS}/" DESTINATION "${SCRATCH}/corpus")
if(NOT SEED)
  set(SEED 1)
endif()
set(options -seed=${SEED})
if(DICT)
  list(APPEND options "-dict=${DICT}")
endif()
execute_process(COMMAND "${TARGET}" ${options} -max_total_time=${SECONDS} -max_len=65536 -timeout=10
                        -rss_limit_mb=1024 -print_final_stats=1 "-artifact_prefix=${SCRATCH}/artifacts/" "${SCRATCH}/corpus"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
string(REGEX MATCHALL "stat::[a-z_]+:[ \t]*[0-9]+" stats "${err}")
string(REGEX MATCH "#[0-9]+[^\n]*DONE[^\n]*" done "${err}")
message(STATUS "${done}")
foreach(s IN LISTS stats)
  message(STATUS "${s}")
endforeach()
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "fuzz target failed (exit ${rc}); reproducer in ${SCRATCH}/artifacts\n${err}")
endif()
