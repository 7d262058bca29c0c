# Compiles each SIMD kernel unit with an ISA's flags and -fsyntax-only (every
# template instantiated, no code emitted), with the project's warnings as
# errors: the check of an ISA that a build leaves out (tests/CMakeLists.txt).
# Usage: cmake -DCXX=<c++> -DFLAGS=<f;...> -DROOT=<source dir> -DFILES=<a;b;...> -P CheckIsaUnits.cmake
foreach(f IN LISTS FILES)
  execute_process(COMMAND ${CXX} -std=c++20 -I${ROOT} ${FLAGS} -ffp-contract=off -fno-fast-math -Wall -Wextra
                          -Wpedantic -Wshadow -Wno-unused-parameter -Werror -fsyntax-only ${f}
                  RESULT_VARIABLE rc ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "CheckIsaUnits: ${f} does not compile with ${FLAGS}:\n${err}")
  endif()
  message(STATUS "${f}: compiles with ${FLAGS}")
endforeach()
