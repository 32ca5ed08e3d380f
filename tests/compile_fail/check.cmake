# Mistakes that must not compile, and the first error each must give (the messages of
# include/sesi/chart.hpp and system.hpp, shown in docs/concepts.md). Run by ctest
# (tests/core/CMakeLists.txt) with CXX, SOURCE_DIR and EIGEN_INCLUDE.
set(cases
  "missing_kinetic_dq|sesi: the chart needs `Scalar kinetic_dq(int i, int k, const Point& q, Scalar p_i, Scalar m) const`"
  "wrong_term|sesi: a potential term must model ExternalTerm")
foreach(entry IN LISTS cases)
  string(FIND "${entry}" "|" bar)
  string(SUBSTRING "${entry}" 0 ${bar} name)
  math(EXPR start "${bar} + 1")
  string(SUBSTRING "${entry}" ${start} -1 expected)
  execute_process(
    COMMAND ${CXX} -std=c++20 -fsyntax-only -I${SOURCE_DIR}/include -I${EIGEN_INCLUDE}
            ${SOURCE_DIR}/tests/compile_fail/${name}.cpp
    RESULT_VARIABLE rc ERROR_VARIABLE output OUTPUT_VARIABLE output_out)
  if(rc EQUAL 0)
    message(FATAL_ERROR "${name}.cpp compiled; it must not")
  endif()
  string(REGEX MATCH "error:[^\n]*" first "${output}")
  string(FIND "${first}" "${expected}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "${name}.cpp: the first error is\n  ${first}\nexpected it to contain\n  ${expected}")
  endif()
  message(STATUS "${name}.cpp: ${first}")
endforeach()
