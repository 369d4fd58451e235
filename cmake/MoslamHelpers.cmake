# Helpers that keep every module's CMakeLists.txt short and uniform.
#
#   moslam_module(<name> SOURCES ... DEPS ...)   -> library target moslam_<name>, alias moslam::<name>
#   moslam_test(<module> <name> SOURCES ... DEPS ... [SHARDS n] [COST seconds] [THREADS])
#       -> test binary, registered as <module>/<name>; with SHARDS n as n tests <module>/<name>/k
#          (GoogleTest's sharding: test k of n runs every n-th test case), so that the long
#          whole-system tests of one file run side by side under `ctest -j`; COST: the seconds
#          it takes in a release build, so that ctest starts the long ones first; THREADS: the
#          test runs code in several threads, so the ThreadSanitizer build runs it (label
#          `threads`, built by the target `threaded_tests`: scripts/test.sh tsan)
#   moslam_benchmark(<name> SOURCES ... DEPS ...)     -> Google Benchmark program (not a test)

function(moslam_module name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_library(moslam_${name} ${ARG_SOURCES})
  add_library(moslam::${name} ALIAS moslam_${name})
  # Headers are included as "moslam/<module>/<file>.h", from the source tree or, installed
  # (cmake/MoslamInstall.cmake), from <prefix>/include.
  target_include_directories(moslam_${name} PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/src>
                                                   $<INSTALL_INTERFACE:include>)
  target_link_libraries(moslam_${name} PUBLIC ${ARG_DEPS})
endfunction()

function(moslam_test module name)
  if(NOT MOSLAM_BUILD_TESTS)
    return()
  endif()
  cmake_parse_arguments(ARG "THREADS" "SHARDS;COST" "SOURCES;DEPS" ${ARGN})
  set(target test_${module}_${name})
  if(MOSLAM_SANITIZE STREQUAL "thread")
    # OpenCV's loops in the calling thread (src/moslam/testing/serial_opencv.cc says why).
    list(APPEND ARG_SOURCES ${PROJECT_SOURCE_DIR}/src/moslam/testing/serial_opencv.cc)
  endif()
  add_executable(${target} ${ARG_SOURCES})
  target_link_libraries(${target} PRIVATE ${ARG_DEPS} moslam::testing GTest::gtest GTest::gmock
                                          GTest::gtest_main)
  if(NOT ARG_SHARDS)
    set(ARG_SHARDS 1)
  endif()
  if(NOT ARG_COST)
    set(ARG_COST 0)
  endif()
  set(labels ${module})
  if(ARG_THREADS)
    list(APPEND labels threads)
    add_dependencies(threaded_tests ${target})
  endif()
  math(EXPR last "${ARG_SHARDS} - 1")
  foreach(k RANGE ${last})
    if(ARG_SHARDS EQUAL 1)
      set(test_name ${module}/${name})
      set(shard_env "")
    else()
      set(test_name ${module}/${name}/${k})
      set(shard_env "GTEST_TOTAL_SHARDS=${ARG_SHARDS};GTEST_SHARD_INDEX=${k}")
    endif()
    add_test(NAME ${test_name} COMMAND ${target})
    # Tests run from the source tree so that relative paths in messages are short; shared data
    # is found through MOSLAM_SHARED (see src/moslam/testing/shared_data.h).
    # OMP_WAIT_POLICY: libtorch's OpenMP threads must not spin while ctest runs tests in
    # parallel (apps/moslam/main.cc says why).
    set_tests_properties(${test_name} PROPERTIES WORKING_DIRECTORY ${PROJECT_SOURCE_DIR}
                                                 LABELS "${labels}"
                                                 COST ${ARG_COST}
                                                 ENVIRONMENT "OMP_WAIT_POLICY=passive;${shard_env}")
  endforeach()
endfunction()

function(moslam_benchmark name)
  if(NOT MOSLAM_BUILD_BENCHMARKS)
    return()
  endif()
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_executable(bench_${name} ${ARG_SOURCES})
  target_link_libraries(bench_${name} PRIVATE ${ARG_DEPS} moslam::testing benchmark::benchmark
                                              benchmark::benchmark_main)
endfunction()
