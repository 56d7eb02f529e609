# Proves the exported package works, in two ctest steps (run with cmake -P):
#   -DSTEP=install  : cmake --install BUILD_DIR into a fresh PREFIX (the fixture setup)
#   -DSTEP=consumer : configure tests/consumer with CMAKE_PREFIX_PATH=PREFIX, build it,
#                     check it found the package in PREFIX (not the build tree), run it.
# Other inputs: BUILD_DIR, PREFIX, CONFIG, and for the consumer step CONSUMER_SOURCE_DIR,
# CONSUMER_BINARY_DIR, GENERATOR, MAKE_PROGRAM, CXX_COMPILER (the parent's toolchain, so
# the consumer is built the way the package was), SOURCE_DIR and, when the tool is built,
# SHTOOL (its path: a fit-zh output of data/spot.obj is made for the consumer to shade),
# SANITIZE (ON: the package was built with sanitizers; the consumer is too).
cmake_minimum_required(VERSION 3.20)

foreach(var STEP BUILD_DIR PREFIX)
  if(NOT DEFINED ${var} OR "${${var}}" STREQUAL "")
    message(FATAL_ERROR "run_consumer_test.cmake: -D${var}=... is required")
  endif()
endforeach()
if(NOT CONFIG)
  set(CONFIG Release)
endif()

# Runs a command; on failure prints the command and everything it wrote, then stops.
function(run_step what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    list(JOIN ARGN " " cmd)
    message(FATAL_ERROR "${what} FAILED (exit ${rc})\n  command: ${cmd}\n"
                        "--- stdout ---\n${out}\n--- stderr ---\n${err}")
  endif()
  message(STATUS "${what}: ok")
  set(step_output "${out}" PARENT_SCOPE)
endfunction()

if(STEP STREQUAL "install")
  # A fresh prefix each run: files left over from an earlier install must not be able
  # to make a broken install look complete.
  file(REMOVE_RECURSE "${PREFIX}")
  run_step("install ${BUILD_DIR} -> ${PREFIX}"
           "${CMAKE_COMMAND}" --install "${BUILD_DIR}" --prefix "${PREFIX}" --config "${CONFIG}")
  file(GLOB_RECURSE configs "${PREFIX}/*/shtoolConfig.cmake")
  if(NOT configs)
    message(FATAL_ERROR "install put no shtoolConfig.cmake under ${PREFIX}")
  endif()
  foreach(header shtool/sh.h shtool/version.h)
    if(NOT EXISTS "${PREFIX}/include/${header}")
      message(FATAL_ERROR "install did not put ${header} under ${PREFIX}/include")
    endif()
  endforeach()

elseif(STEP STREQUAL "consumer")
  foreach(var CONSUMER_SOURCE_DIR CONSUMER_BINARY_DIR)
    if(NOT DEFINED ${var} OR "${${var}}" STREQUAL "")
      message(FATAL_ERROR "run_consumer_test.cmake: -D${var}=... is required")
    endif()
  endforeach()
  file(REMOVE_RECURSE "${CONSUMER_BINARY_DIR}")
  set(configure_args -S "${CONSUMER_SOURCE_DIR}" -B "${CONSUMER_BINARY_DIR}"
      "-DCMAKE_PREFIX_PATH=${PREFIX}" "-DCMAKE_BUILD_TYPE=${CONFIG}"
      # Only the scratch prefix may satisfy find_package(shtool): no user or system
      # package registry entries pointing back at some build tree.
      -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF -DCMAKE_FIND_USE_SYSTEM_PACKAGE_REGISTRY=OFF
      # An engine needs no JSON library: the package must configure without one.
      -DCMAKE_DISABLE_FIND_PACKAGE_nlohmann_json=ON)
  if(GENERATOR)
    list(APPEND configure_args -G "${GENERATOR}")
  endif()
  if(MAKE_PROGRAM)
    list(APPEND configure_args "-DCMAKE_MAKE_PROGRAM=${MAKE_PROGRAM}")
  endif()
  if(CXX_COMPILER)
    list(APPEND configure_args "-DCMAKE_CXX_COMPILER=${CXX_COMPILER}")
  endif()
  # A sanitizer build of the package is consumed with the same instrumentation, but for
  # UBSan's vptr check, which needs RTTI (the consumer is built with -fno-rtti).
  if(SANITIZE)
    list(APPEND configure_args
         "-DCMAKE_CXX_FLAGS=-fsanitize=address,undefined -fno-sanitize=vptr -fno-sanitize-recover=all"
         "-DCMAKE_EXE_LINKER_FLAGS=-fsanitize=address,undefined")
  endif()
  run_step("configure consumer" "${CMAKE_COMMAND}" ${configure_args})

  # The package must come from the install, never from the build tree.
  file(STRINGS "${CONSUMER_BINARY_DIR}/CMakeCache.txt" found_dir REGEX "^shtool_DIR:")
  string(REGEX REPLACE "^shtool_DIR:[A-Z]+=" "" found_dir "${found_dir}")
  file(REAL_PATH "${PREFIX}" real_prefix)
  file(REAL_PATH "${found_dir}" real_found)
  string(FIND "${real_found}/" "${real_prefix}/" at)
  if(NOT at EQUAL 0)
    message(FATAL_ERROR "consumer found shtool in '${found_dir}', not under the install "
                        "prefix '${PREFIX}'")
  endif()
  message(STATUS "consumer uses ${found_dir}")

  # docs/engine.md shows engine_example.cpp: its one C++ block must be the file, byte for byte.
  if(SOURCE_DIR)
    file(READ "${SOURCE_DIR}/docs/engine.md" doc)
    file(READ "${CONSUMER_SOURCE_DIR}/engine_example.cpp" example)
    string(FIND "${doc}" "```cpp\n" open)
    string(FIND "${doc}" "\n```\n" close REVERSE)
    if(open EQUAL -1 OR close EQUAL -1)
      message(FATAL_ERROR "docs/engine.md has no ```cpp block")
    endif()
    math(EXPR first "${open} + 7")
    math(EXPR length "${close} + 1 - ${first}")
    string(SUBSTRING "${doc}" ${first} ${length} block)
    if(NOT block STREQUAL example)
      message(FATAL_ERROR "the code block of docs/engine.md differs from tests/consumer/engine_example.cpp")
    endif()
    message(STATUS "docs/engine.md shows engine_example.cpp as it is")
  endif()
  run_step("build consumer" "${CMAKE_COMMAND}" --build "${CONSUMER_BINARY_DIR}" --config "${CONFIG}")

  find_program(consumer_exe consumer PATHS "${CONSUMER_BINARY_DIR}" "${CONSUMER_BINARY_DIR}/${CONFIG}"
               NO_DEFAULT_PATH REQUIRED)
  # The shipped tables as an engine finds them: SHTOOL_TABLES naming the installed folder.
  set(tables "${PREFIX}/share/shtool/tables")
  if(NOT EXISTS "${tables}/rotation-helpers.shtb")
    message(FATAL_ERROR "install did not put the shipped tables in ${tables}")
  endif()
  # A fit-zh output to shade, made by the built tool (absent when only the runtime is built).
  set(fit_args)
  if(SHTOOL)
    set(fit "${CONSUMER_BINARY_DIR}/spot.zh.shtb")
    run_step("fit-zh for the consumer" "${SHTOOL}" fit-zh "${SOURCE_DIR}/data/spot.obj" --order 4 --lobes 2
             --rays 64 --out "${fit}")
    set(lighting "${CONSUMER_BINARY_DIR}/sky.env.shtb")
    run_step("light for the consumer" "${SHTOOL}" light --type hemisphere --dir 0.3,0.2,0.9 --color 1,0.8,0.6
             --ground 0.1,0.1,0.2 --order 5 --json "${CONSUMER_BINARY_DIR}/sky.json" --out "${lighting}")
    set(probes "${CONSUMER_BINARY_DIR}/spot.probes.shtb")
    run_step("bake-probes for the consumer" "${SHTOOL}" bake-probes "${SOURCE_DIR}/data/spot.obj" --grid 2,2,2
             --samples 16 --bounces 1 --out "${probes}")
    set(low_lighting "${CONSUMER_BINARY_DIR}/low.env.shtb")
    run_step("lower-order light for the consumer" "${SHTOOL}" light --type directional --dir 0,0,1 --order 3
             --json "${CONSUMER_BINARY_DIR}/low.json" --out "${low_lighting}")
    set(fit_args "${fit}" "${lighting}" "${probes}" "${low_lighting}")
  endif()
  run_step("run consumer" "${CMAKE_COMMAND}" -E env "SHTOOL_TABLES=${tables}" "${consumer_exe}" ${fit_args})
  message(STATUS "${step_output}")

else()
  message(FATAL_ERROR "run_consumer_test.cmake: unknown STEP '${STEP}' (install or consumer)")
endif()
