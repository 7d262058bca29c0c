# Script mode: every file of kernels/ compiles on its own.
#  - each header as C++20, included alone (after kernels/types.h) in a
#    namespace, as the instances include them (host/scalar/kernel_instance.inc);
#  - each header and .cl file as OpenCL C 1.2 with clang (when CLANG is set),
#    in the default precision and in fp64 mode.
# Usage: cmake -DCXX=<c++> -DCLANG=<clang or empty> -DROOT=<source dir>
#              -DWORK=<scratch dir> -P CheckKernelHeaders.cmake
file(GLOB headers ${ROOT}/kernels/*.h)
file(GLOB cls ${ROOT}/kernels/*.cl)
file(MAKE_DIRECTORY ${WORK})
set(failed "")
foreach(h IN LISTS headers)
  get_filename_component(name ${h} NAME)
  set(tu ${WORK}/check_${name}.cpp)
  file(WRITE ${tu} "#include \"kernels/types.h\"\nnamespace cr::header_check {\n#include \"kernels/${name}\"\n}\n")
  execute_process(COMMAND ${CXX} -std=c++20 -fsyntax-only -Wall -Wextra -Wpedantic -Wshadow -Wno-unused-parameter -Werror -I${ROOT} ${tu}
                  RESULT_VARIABLE rc ERROR_VARIABLE err OUTPUT_QUIET)
  if(NOT rc EQUAL 0)
    list(APPEND failed "C++ ${name}:\n${err}")
  endif()
endforeach()
# OpenCL C 1.2 has no variadic macros: clang accepts them, NVIDIA's OpenCL
# compiler does not ("variadic macros not supported in OpenCL").
foreach(f IN LISTS headers cls)
  get_filename_component(name ${f} NAME)
  file(STRINGS ${f} variadic REGEX "#[ \t]*define[ \t]+[A-Za-z_0-9]+\\([^)]*\\.\\.\\.")
  if(variadic)
    list(APPEND failed "OpenCL C ${name}: a variadic macro (not OpenCL C 1.2; NVIDIA's compiler rejects it):\n${variadic}")
  endif()
endforeach()
if(CLANG)
  foreach(f IN LISTS headers cls)
    get_filename_component(name ${f} NAME)
    foreach(mode "" "-DCR_FP64")
      execute_process(COMMAND ${CLANG} -x cl -cl-std=CL1.2 -fsyntax-only -Xclang -finclude-default-header ${mode}
                              -I${ROOT}/kernels ${f}
                      RESULT_VARIABLE rc ERROR_VARIABLE err OUTPUT_QUIET)
      if(NOT rc EQUAL 0)
        list(APPEND failed "OpenCL C ${mode} ${name}:\n${err}")
      endif()
    endforeach()
  endforeach()
endif()
if(failed)
  string(REPLACE ";" "\n" msg "${failed}")
  message(FATAL_ERROR "kernel files that do not compile on their own:\n${msg}")
endif()
list(LENGTH headers nh)
list(LENGTH cls ncl)
message(STATUS "kernels: ${nh} headers compile alone as C++; OpenCL C: ${CLANG}")
