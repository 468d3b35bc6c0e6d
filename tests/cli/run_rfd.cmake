# Shared by the CLI test scripts: run(CODE ARGS...) runs `rfd --quiet ARGS...`, fails unless
# it exits with CODE, and leaves its stdout and stderr in `last_output`; expect(REGEX) fails
# unless `last_output` matches.
function(run expected_code)
  execute_process(COMMAND ${RFD} --quiet ${ARGN} RESULT_VARIABLE code OUTPUT_VARIABLE stdout ERROR_VARIABLE stderr)
  if(NOT code EQUAL expected_code)
    message(FATAL_ERROR "rfd ${ARGN}: exit ${code}, expected ${expected_code}\n${stdout}\n${stderr}")
  endif()
  set(last_output "${stdout}${stderr}" PARENT_SCOPE)
endfunction()
function(expect pattern)
  if(NOT last_output MATCHES "${pattern}")
    message(FATAL_ERROR "expected '${pattern}' in:\n${last_output}")
  endif()
endfunction()
# expect_same_file(A B WHY): fails with WHY unless files A and B hold the same bytes.
function(expect_same_file a b why)
  file(SHA256 ${a} hash_a)
  file(SHA256 ${b} hash_b)
  if(NOT hash_a STREQUAL hash_b)
    message(FATAL_ERROR "${why}: ${a} and ${b} differ")
  endif()
endfunction()
