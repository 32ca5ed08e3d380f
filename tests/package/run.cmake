# Installs the sesi build tree into a fresh prefix, then builds and runs the consumer project
# against it with find_package(sesi CONFIG REQUIRED), with and without Boost. Run by ctest
# (tests/CMakeLists.txt).
file(REMOVE_RECURSE ${WORK_DIR})
set(prefix ${WORK_DIR}/prefix)
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}")
  endif()
endfunction()
run(${CMAKE_COMMAND} --install ${SESI_BUILD_DIR} --prefix ${prefix})
run(${CMAKE_COMMAND} -S ${CONSUMER_SOURCE_DIR} -B ${WORK_DIR}/build
    -D CMAKE_PREFIX_PATH=${prefix} -D CMAKE_CXX_COMPILER=${CXX_COMPILER} -D CMAKE_BUILD_TYPE=Release)
run(${CMAKE_COMMAND} --build ${WORK_DIR}/build)
run(${WORK_DIR}/build/consumer)
run(${WORK_DIR}/build/consumer_torus)
run(${WORK_DIR}/build/consumer_odeint)
# A consumer of sesi::sesi alone on a machine without Boost (Boost hidden from find_package).
run(${CMAKE_COMMAND} -S ${CONSUMER_SOURCE_DIR} -B ${WORK_DIR}/build-no-boost -D ODEINT=OFF
    -D CMAKE_DISABLE_FIND_PACKAGE_Boost=ON
    -D CMAKE_PREFIX_PATH=${prefix} -D CMAKE_CXX_COMPILER=${CXX_COMPILER} -D CMAKE_BUILD_TYPE=Release)
run(${CMAKE_COMMAND} --build ${WORK_DIR}/build-no-boost)
run(${WORK_DIR}/build-no-boost/consumer)
run(${WORK_DIR}/build-no-boost/consumer_torus)
