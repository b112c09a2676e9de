# builtscene_module(NAME SOURCES... DEPS ...): a static library `bs_<NAME>` from src/<NAME>.
# Headers are included as "<module>/<file>.hpp" with src/ on the include path.
function(builtscene_module name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_library(bs_${name} STATIC ${ARG_SOURCES})
  target_include_directories(bs_${name} PUBLIC ${PROJECT_SOURCE_DIR}/src)
  target_link_libraries(bs_${name} PUBLIC ${ARG_DEPS} PRIVATE builtscene_warnings)
endfunction()

# builtscene_test(NAME SOURCES... DEPS ... LABELS ...): one GoogleTest executable, every
# TEST registered with ctest. Label `unit` (default) runs under the sanitizers too;
# `slow` marks the bounded end-to-end tests.
function(builtscene_test name)
  cmake_parse_arguments(ARG "" "TIMEOUT" "SOURCES;DEPS;LABELS" ${ARGN})
  if(NOT ARG_LABELS)
    set(ARG_LABELS unit)
  endif()
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 600)
  endif()
  # The sanitizer tree runs only the unit label: a test executable without it is not built there.
  if(BUILTSCENE_SANITIZE AND NOT "unit" IN_LIST ARG_LABELS)
    return()
  endif()
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS} GTest::gtest GTest::gtest_main builtscene_warnings)
  target_compile_definitions(${name} PRIVATE
    BUILTSCENE_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    BUILTSCENE_BINARY="$<TARGET_FILE:builtscene>")
  add_dependencies(${name} builtscene)
  # ctest starts costlier tests first: on a fresh tree (no CTestCostData.txt yet) the slow
  # end-to-end tests, longest timeout first, so that none of them is left running alone at
  # the end of a parallel run.
  set(cost 0)
  if("slow" IN_LIST ARG_LABELS)
    set(cost ${ARG_TIMEOUT})
  endif()
  gtest_discover_tests(${name}
    WORKING_DIRECTORY ${PROJECT_SOURCE_DIR}
    PROPERTIES LABELS "${ARG_LABELS}" TIMEOUT ${ARG_TIMEOUT} COST ${cost}
    DISCOVERY_TIMEOUT 60)
endfunction()
