# CTest labels (issue 23), read by ctest after the doctest cases are registered (a
# TEST_INCLUDE_FILES script, see tests/CMakeLists.txt, which sets the test_*_exe paths).
#   unit         core/ and maps/ cases, and the server's cases that start no server or process
#   integration  server cases over loopback (the CLI and serve scripts and the golden results are
#                labelled where tests/CMakeLists.txt adds them)
#   slow         over ~10 s on a 2-core machine (measured with ctest -j2), whatever else they are
# A server source file is unit only if none of its cases start a server; a file that mixes both
# is integration as a whole. The browser tests (tests/browser, node) are not registered in CTest. `ctest -L unit -LE slow` is the fast local run.

# The doctest cases of `exe` defined in sources matching `pattern`.
function(rover_cases out exe pattern)
  execute_process(COMMAND "${exe}" --list-test-cases "--source-file=${pattern}"
                  OUTPUT_VARIABLE listing RESULT_VARIABLE rc)
  set(cases "")
  if(rc EQUAL 0)
    string(REPLACE "\n" ";" lines "${listing}")
    foreach(line IN LISTS lines)
      if(line STREQUAL "" OR line MATCHES "^\\[doctest\\] " OR line MATCHES "^=+$")
        continue()
      endif()
      list(APPEND cases "${line}")
    endforeach()
  endif()
  set(${out} "${cases}" PARENT_SCOPE)
endfunction()

# Measured over 10 s (ctest --test-dir build -j2 on the 2-core machine): regexes over CTest names.
set(rover_slow_tests
  "^server/a study database opened while another connection creates it"
  "^maps/team planners on every DEM"
  "^server/same origin: without a token"
  "^server/host allow-list"
  "^server/hostile missions: a subscriber that never reads"
)

# `label`, and slow if `test` is one of rover_slow_tests.
function(rover_labels_of out test label)
  set(labels "${label}")
  foreach(slow IN LISTS rover_slow_tests)
    if(test MATCHES "${slow}")
      list(APPEND labels slow)
      break()
    endif()
  endforeach()
  set(${out} "${labels}" PARENT_SCOPE)
endfunction()

# Labels every case of `exe` (CTest name prefix + case) from sources matching `pattern`.
function(rover_label exe prefix pattern label)
  rover_cases(cases "${exe}" "${pattern}")
  foreach(name IN LISTS cases)
    rover_labels_of(labels "${prefix}${name}" ${label})
    set_tests_properties("${prefix}${name}" PROPERTIES LABELS "${labels}")
  endforeach()
endfunction()

rover_label("${test_core_exe}" "core/" "*" unit)
rover_label("${test_maps_exe}" "maps/" "*" unit)
# The server's cases are integration unless their file is one of these (a new file starts there;
# ctest adds labels to those a test has, so each case is labelled once).
set(unit_cases "")
foreach(file arg_parser plan_json cli_commands router store work_pool studies study_ompl mission_stream mcap_writer)
  rover_cases(cases "${test_server_exe}" "*test_${file}.cpp")
  list(APPEND unit_cases ${cases})
endforeach()
rover_cases(server_cases "${test_server_exe}" "*")
foreach(name IN LISTS server_cases)
  list(FIND unit_cases "${name}" at)  # not if(IN_LIST): ctest sets no policies (CMP0057)
  if(at GREATER -1)
    rover_labels_of(labels "server/${name}" unit)
  else()
    rover_labels_of(labels "server/${name}" integration)
  endif()
  set_tests_properties("server/${name}" PROPERTIES LABELS "${labels}")
endforeach()
