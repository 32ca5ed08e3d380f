# Builds the whole test suite with clang under AddressSanitizer + UndefinedBehaviorSanitizer in
# a nested build directory and runs it (issue #5, hardening). Run by ctest as `sanitizers`.
# Tests labelled `long` are left out here: they run in the main build, and under the sanitizers
# they would take most of CI's time without covering more code. So are the reference
# integrators' tests (tests/reference), the many-body and stability tests (template-heavy to
# compile, numerical checks of code the core tests also run), the examples, and the benchmarks
# (tests/bench; SESI_SANITIZER_BUILD builds the program without the scenes of `sesi bench --scene`,
# whose reference steppers took 650 s of clang's CPU): all run in the main build. The job covers
# the program, whose input is untrusted, and the core tests of the library's memory-holding code
# (tests/core/CMakeLists.txt). Tests marked QUICK compile at -O0 in every build
# (tests/CMakeLists.txt), and SESI_SANITIZER_BUILD instantiates fixed-size charts for dimensions 2
# and 3 only (src/integrators/dispatch.hpp) and compiles the Eigen::Dynamic integrators and those
# of the geodesic methods at -O0 (src/CMakeLists.txt). With stability and many-body tests in, a
# fresh-clone `make test` took over an hour on two cores (CI's budget is 45 minutes).
set(dir ${WORK_DIR})
# The outer build's Python (the Makefile's Debian python3, with pytest and h5py), not whichever
# python3 comes first in PATH.
set(python_arg "")
if(PYTHON)
  set(python_arg "-DPython3_EXECUTABLE=${PYTHON}")
endif()
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "sanitizer job failed (${rc}): ${ARGN}")
  endif()
endfunction()
set(flags "-fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer")
# -O1 -g1 (line tables) as the sanitizers' own documentation suggests: on this machine it halves
# clang's time on a template-heavy test file (tests/core/symplectic.cpp: 98 s against 184 s at
# -O2 -g), which keeps `make test` within CI's budget; NDEBUG as in the main build.
run(${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${dir} -G "Unix Makefiles"
    -D CMAKE_BUILD_TYPE=RelWithDebInfo
    -D "CMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG"
    -D CMAKE_CXX_COMPILER=${CLANG}
    -D "CMAKE_CXX_FLAGS=${flags}"
    -D "CMAKE_EXE_LINKER_FLAGS=${flags}"
    -D SESI_WERROR=ON
    -D SESI_SANITIZER_BUILD=ON
    -D SESI_SANITIZER_JOB=OFF
    -D SESI_INSTALL=OFF
    -D SESI_BUILD_EXAMPLES=OFF
    -D SESI_BUILD_BENCHMARKS=OFF
    -D SESI_BUILD_PYTHON=OFF
    -D SESI_TEST_PARTS=core,program
    -D SESI_REQUIRE_ALL_TESTS=${REQUIRE_ALL}
    ${python_arg})
run(${CMAKE_COMMAND} --build ${dir} -j ${JOBS})
run(${CMAKE_CTEST_COMMAND} --test-dir ${dir} --output-on-failure -j ${JOBS} -LE long
    --output-junit ${dir}/ctest-junit.xml)
# Under SESI_REQUIRE_ALL_TESTS (make test) a test skipped here fails the job too.
if(REQUIRE_ALL)
  run(${CMAKE_COMMAND} -D JUNIT=${dir}/ctest-junit.xml -P ${SOURCE_DIR}/tests/check_skips.cmake)
endif()
