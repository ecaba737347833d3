# skelcd_add_module(NAME
#   SOURCES   a.cpp b.cpp            # explicit list, no globbing
#   PUBLIC_DEPS  ...  PRIVATE_DEPS ...
#   TESTS     ../tests/NAME/test_a.cpp ...   # one GoogleTest executable per module
#   TEST_DEPS ...)
# Makes library skelcd_NAME (alias skelcd::NAME) with includes rooted at the repository, and
# registers its test executable skelcd_NAME_tests with gtest_discover_tests.
include(GoogleTest)

#   [WHOLE_ARCHIVE]                  # linked whole: files that only register themselves (a
#                                    # culling method, culling/method_registry.hpp) are kept
function(skelcd_add_module name)
  cmake_parse_arguments(ARG "WHOLE_ARCHIVE" "" "SOURCES;PUBLIC_DEPS;PRIVATE_DEPS;TESTS;TEST_DEPS" ${ARGN})
  add_library(skelcd_${name} STATIC ${ARG_SOURCES})
  if(ARG_WHOLE_ARCHIVE)
    # Everyone links it through the alias, so every link sees the same whole-archive item.
    add_library(skelcd_${name}_whole INTERFACE)
    target_link_libraries(skelcd_${name}_whole INTERFACE "$<LINK_LIBRARY:WHOLE_ARCHIVE,skelcd_${name}>")
    add_library(skelcd::${name} ALIAS skelcd_${name}_whole)
  else()
    add_library(skelcd::${name} ALIAS skelcd_${name})
  endif()
  target_include_directories(skelcd_${name} PUBLIC ${PROJECT_SOURCE_DIR})
  target_compile_features(skelcd_${name} PUBLIC cxx_std_20)
  target_link_libraries(skelcd_${name} PUBLIC ${ARG_PUBLIC_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  target_link_libraries(skelcd_${name} PRIVATE skelcd_warnings)
  if(ARG_TESTS)
    skelcd_add_test_executable(skelcd_${name}_tests
      SOURCES ${ARG_TESTS}
      DEPS skelcd::${name} ${ARG_TEST_DEPS})
  endif()
endfunction()

# A GoogleTest executable whose tests run in ctest's default label.
function(skelcd_add_test_executable target)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_executable(${target} ${ARG_SOURCES})
  target_link_libraries(${target} PRIVATE ${ARG_DEPS} skelcd::test_support GTest::gtest GTest::gmock
                                          GTest::gtest_main skelcd_warnings)
  gtest_discover_tests(${target}
    WORKING_DIRECTORY ${PROJECT_SOURCE_DIR}
    PROPERTIES LABELS unit ENVIRONMENT "${SKELCD_TEST_ENVIRONMENT}"
    DISCOVERY_TIMEOUT 60)
endfunction()

# A Google Benchmark executable under bench/, built with the project but never run by ctest.
function(skelcd_add_benchmark target)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_executable(${target} ${ARG_SOURCES})
  target_link_libraries(${target} PRIVATE ${ARG_DEPS} benchmark::benchmark skelcd_warnings)
  target_compile_definitions(${target} PRIVATE SKELCD_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
endfunction()
