# Cross-process test of the session log: the real world_server records a session with --log
# while a real haptic_node joins and leaves, then the real session_report reads the file.
# Also: a second run appends a session; missing, corrupt and unwritable logs fail with exit
# codes and messages that name the file.
#
# cmake -DWORLD_SERVER=... -DSESSION_REPORT=... -DHAPTIC_NODE=... -DWORK=dir -DDOMAIN=120 -P this
foreach(var WORLD_SERVER SESSION_REPORT HAPTIC_NODE WORK DOMAIN)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "set -D${var}")
  endif()
endforeach()
foreach(exe WORLD_SERVER SESSION_REPORT HAPTIC_NODE)
  if(NOT EXISTS "${${exe}}")
    message(FATAL_ERROR "executable not built: ${${exe}}")
  endif()
endforeach()

file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")
set(log "${WORK}/session.sqlite")
set(session "logtest")

function(expect_in text what)
  string(FIND "${text}" "${what}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "expected '${what}' in:\n${text}")
  endif()
endfunction()

function(expect_rc rc want what)
  if(NOT "${rc}" STREQUAL "${want}")
    message(FATAL_ERROR "${what}: exit code '${rc}', expected ${want}")
  endif()
endfunction()

# 1. Alice joins for 1.5 s of a 4 s session and leaves cleanly. execute_process runs the
#    commands of a pipeline at the same time; the world server is last so it never writes into
#    a closed pipe, and its output is what we read.
execute_process(
  COMMAND "${HAPTIC_NODE}" --domain ${DOMAIN} --session ${session} --user alice --device sim --duration 1.5
  COMMAND "${WORLD_SERVER}" --domain ${DOMAIN} --session ${session} --duration 4 --log "${log}"
  RESULTS_VARIABLE rcs OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 60)
message(STATUS "world_server:\n${out}${err}")
expect_rc("${rcs}" "0;0" "haptic_node;world_server")
expect_in("${out}" "member joined: user=alice")
expect_in("${out}" "member left: user=alice")
expect_in("${out}" "session log ${log}: session #1")
expect_in("${out}" "session #1 written")

execute_process(COMMAND "${SESSION_REPORT}" "${log}" RESULT_VARIABLE rc OUTPUT_VARIABLE report ERROR_VARIABLE err)
message(STATUS "session_report:\n${report}${err}")
expect_rc("${rc}" 0 "session_report")
expect_in("${report}" "1 session(s), showing #1")
expect_in("${report}" "session #1 '${session}' on DDS domain ${DOMAIN}")
expect_in("${report}" "members: 1 stay(s)")
string(REGEX MATCH "alice +haptic +sim +[0-9.]+ +[0-9.]+  left" stay "${report}")
if(NOT stay)
  message(FATAL_ERROR "no line for alice's stay (joined, left) in the report")
endif()
expect_in("${report}" "start_menu")
expect_in("${report}" "(no control events logged)")

execute_process(COMMAND "${SESSION_REPORT}" "${log}" --csv RESULT_VARIABLE rc OUTPUT_VARIABLE csv ERROR_VARIABLE err)
expect_rc("${rc}" 0 "session_report --csv")
expect_in("${csv}" "session,section,item,field,value\n")
expect_in("${csv}" "1,member,${session}/alice#1,how,left\n")
string(REGEX MATCH "1,world,start_menu,seconds,([0-9.]+)" m "${csv}")
if(NOT m)
  message(FATAL_ERROR "no start_menu time in the CSV:\n${csv}")
endif()
# The scene is published after DDS setup and the session ends at 4 s: 3 to 4.5 s in the world.
if(CMAKE_MATCH_1 LESS 3.0 OR CMAKE_MATCH_1 GREATER 4.5)
  message(FATAL_ERROR "start_menu time ${CMAKE_MATCH_1} s, expected 3 to 4.5 s")
endif()
string(REGEX MATCH "1,member,${session}/alice#1,joined_s,([0-9.]+)" m "${csv}")
set(joined ${CMAKE_MATCH_1})
string(REGEX MATCH "1,member,${session}/alice#1,gone_s,([0-9.]+)" m "${csv}")
set(gone ${CMAKE_MATCH_1})
if(NOT joined OR NOT gone OR gone LESS joined)
  message(FATAL_ERROR "alice's stay: joined '${joined}' s, gone '${gone}' s")
endif()

# 2. A second run on the same file appends session #2 (another world this time).
execute_process(
  COMMAND "${WORLD_SERVER}" --domain ${DOMAIN} --session second --scene solar_system --duration 1 --log "${log}"
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 60)
expect_rc("${rc}" 0 "world_server (second run)")
expect_in("${out}" "session #2")
execute_process(COMMAND "${SESSION_REPORT}" "${log}" RESULT_VARIABLE rc OUTPUT_VARIABLE report ERROR_VARIABLE err)
expect_rc("${rc}" 0 "session_report (newest)")
expect_in("${report}" "2 session(s), showing #2")
expect_in("${report}" "session #2 'second'")
expect_in("${report}" "solar_system")
expect_in("${report}" "members: 0 stay(s)")
execute_process(COMMAND "${SESSION_REPORT}" "${log}" --session 1 RESULT_VARIABLE rc OUTPUT_VARIABLE report ERROR_VARIABLE err)
expect_rc("${rc}" 0 "session_report --session 1")
expect_in("${report}" "session #1 '${session}'")
execute_process(COMMAND "${SESSION_REPORT}" "${log}" --session 9 RESULT_VARIABLE rc OUTPUT_VARIABLE report ERROR_VARIABLE err)
expect_rc("${rc}" 2 "session_report --session 9")
expect_in("${err}" "no session 9")

# 3. Missing, corrupt and foreign files, and bad arguments: exit 2 with the reason.
execute_process(COMMAND "${SESSION_REPORT}" "${WORK}/absent.sqlite" RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect_rc("${rc}" 2 "session_report on a missing file")
expect_in("${err}" "${WORK}/absent.sqlite: no such file")
file(WRITE "${WORK}/corrupt.sqlite" "This is a text file pretending to be a session log, long enough to pass as a header.\n")
execute_process(COMMAND "${SESSION_REPORT}" "${WORK}/corrupt.sqlite" RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect_rc("${rc}" 2 "session_report on a corrupt file")
expect_in("${err}" "${WORK}/corrupt.sqlite")
expect_in("${err}" "not a database")
execute_process(COMMAND "${SESSION_REPORT}" RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
expect_rc("${rc}" 2 "session_report without a file")
expect_in("${err}" "missing the session log FILE")

# 4. The world server refuses a log it cannot write, before joining the session.
execute_process(
  COMMAND "${WORLD_SERVER}" --domain ${DOMAIN} --session x --duration 1 --log "${WORK}/no/such/folder/log.sqlite"
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 60)
expect_rc("${rc}" 1 "world_server --log in a missing folder")
expect_in("${err}" "${WORK}/no/such/folder/log.sqlite")
expect_in("${err}" "unable to open database file")
execute_process(
  COMMAND "${WORLD_SERVER}" --domain ${DOMAIN} --session x --duration 1 --log "${WORK}/corrupt.sqlite"
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 60)
expect_rc("${rc}" 1 "world_server --log on a corrupt file")
expect_in("${err}" "not a database")

# 5. A killed server (execute_process's timeout kills it) leaves a readable log whose session
#    has no end: the report runs it until the writer's last heartbeat (once a second).
set(killed_log "${WORK}/killed.sqlite")
execute_process(
  COMMAND "${WORLD_SERVER}" --domain ${DOMAIN} --session killed --duration 60 --log "${killed_log}"
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 3)
if(rc EQUAL 0)
  message(FATAL_ERROR "world_server was not killed: rc ${rc}\n${out}")
endif()
find_program(FASTDDS fastdds)
if(FASTDDS)  # the killed participant's shared-memory segments (only unused ones are removed)
  execute_process(COMMAND "${FASTDDS}" shm clean OUTPUT_QUIET ERROR_QUIET)
endif()
execute_process(COMMAND "${SESSION_REPORT}" "${killed_log}" --csv RESULT_VARIABLE rc OUTPUT_VARIABLE csv ERROR_VARIABLE err)
expect_rc("${rc}" 0 "session_report on a killed server's log")
expect_in("${csv}" "1,session,1,ended_unix_ns,\n")
string(REGEX MATCH "1,session,1,duration_s,([0-9.]+)" m "${csv}")
if(NOT m OR CMAKE_MATCH_1 LESS 1.0 OR CMAKE_MATCH_1 GREATER 3.5)
  message(FATAL_ERROR "killed session: duration '${CMAKE_MATCH_1}' s, expected 1 to 3.5 s (last heartbeat)\n${csv}")
endif()
message(STATUS "session log round trip: all checks passed")
