# Installs the built project into a scratch prefix, then configures, builds and runs a small
# controller-like project that uses find_package(pbppo-rt) and links pbppo::runtime.
file(REMOVE_RECURSE ${WORK})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK}/prefix
  RESULT_VARIABLE rc OUTPUT_QUIET)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "cmake --install failed (${rc})")
endif()
# On a cross-build (TOOLCHAIN, EMULATOR: its words joined by '|'), the consumer is cross-built with
# the same toolchain file and runs through the emulator.
set(expected lib/cmake/pbppo-rt/pbppo-rtConfig.cmake include/pbppo-rt/runtime/policy/policy_model.hpp
  bin/pbppo-controller)
if(TOOLS)
  list(APPEND expected bin/pbppo)
endif()
string(REPLACE "|" ";" run "${EMULATOR}")
set(cross "")
if(TOOLCHAIN)
  # The installed tree is outside the toolchain's root, where packages are searched: named.
  set(cross -DCMAKE_TOOLCHAIN_FILE=${TOOLCHAIN} -Dpbppo-rt_DIR=${WORK}/prefix/lib/cmake/pbppo-rt)
endif()
foreach(f ${expected})
  if(NOT EXISTS ${WORK}/prefix/${f})
    message(FATAL_ERROR "not installed: ${f}")
  endif()
endforeach()
execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE_DIR}/tests/install/consumer -B ${WORK}/build
  -G ${GENERATOR} -DCMAKE_CXX_COMPILER=${CXX} -DCMAKE_PREFIX_PATH=${WORK}/prefix -DCMAKE_BUILD_TYPE=Release ${cross}
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "consumer configure failed:\n${out}\n${err}")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${WORK}/build RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "consumer build failed:\n${out}\n${err}")
endif()
execute_process(COMMAND ${run} ${WORK}/build/consumer ${SOURCE_DIR}/tests/data/blobs/p3.blob
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "consumer failed (${rc}):\n${out}\n${err}")
endif()
message(STATUS "${out}")
# The DDS transport from the installed tree, with the installed profile (domain 231: outside the
# 10-229 that the dds tests draw from).
set(profile ${WORK}/prefix/share/pbppo-rt/dds_profile.xml)
if(NOT EXISTS ${profile})
  message(FATAL_ERROR "not installed: share/pbppo-rt/dds_profile.xml")
endif()
execute_process(COMMAND ${run} ${WORK}/build/consumer_dds ${SOURCE_DIR}/models/auv/robot.yaml ${profile} 231 TIMEOUT 60
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "consumer_dds failed (${rc}):\n${out}\n${err}")
endif()
message(STATUS "${out}")
