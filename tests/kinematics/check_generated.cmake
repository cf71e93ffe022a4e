# ctest script: regenerate the robot URDFs into OUT and require them identical to the committed ones,
# so config/robots/*.urdf cannot drift from the numbers documented in gen_urdf.py.
# Variables: PY (python3), GEN (gen_urdf.py), OUT (scratch dir), ROBOTS (config/robots).
execute_process(COMMAND "${PY}" "${GEN}" --out "${OUT}" RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${GEN} failed (${rc})")
endif()
foreach(f jaco2.urdf mico2.urdf pa10plus.urdf)
  execute_process(COMMAND "${CMAKE_COMMAND}" -E compare_files "${OUT}/${f}" "${ROBOTS}/${f}" RESULT_VARIABLE same)
  if(NOT same EQUAL 0)
    message(FATAL_ERROR "${ROBOTS}/${f} differs from the output of ${GEN}; regenerate and commit it")
  endif()
endforeach()
message(STATUS "robot URDFs match ${GEN}")
