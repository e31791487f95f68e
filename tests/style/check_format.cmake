# Fails if clang-format would change any C++ file under the project's source folders.
file(GLOB_RECURSE files
  ${SOURCE_DIR}/runtime/*.cpp ${SOURCE_DIR}/runtime/*.hpp
  ${SOURCE_DIR}/firmware/*.cpp ${SOURCE_DIR}/firmware/*.hpp
  ${SOURCE_DIR}/sim_hil/*.cpp ${SOURCE_DIR}/sim_hil/*.hpp
  ${SOURCE_DIR}/policies/*.cpp ${SOURCE_DIR}/policies/*.hpp
  ${SOURCE_DIR}/bench/*.cpp ${SOURCE_DIR}/bench/*.hpp
  ${SOURCE_DIR}/tests/*.cpp ${SOURCE_DIR}/tests/*.hpp)
list(LENGTH files n)
execute_process(COMMAND ${CLANG_FORMAT} --dry-run --Werror ${files}
  RESULT_VARIABLE rc ERROR_VARIABLE err OUTPUT_QUIET)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "clang-format would change these files (run: clang-format-19 -i FILE):\n${err}")
endif()
message(STATUS "clang-format: ${n} files clean")
