# Fails when an object compiled with ISA flags (simd/kernels_*.cpp) defines a
# weak symbol outside its ISA namespace: the linker could pick that copy (say
# an AVX2-encoded std::fabs) for the whole program, which would then crash
# on a CPU without the ISA. See docs/SIMD.md, "ISA dispatch and the build".
# Usage: cmake -DNM=<nm> -DOBJECTS=<a;b;...> -P CheckIsaSymbols.cmake
foreach(obj IN LISTS OBJECTS)
  execute_process(COMMAND ${NM} -C ${obj} OUTPUT_VARIABLE syms RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "CheckIsaSymbols: ${NM} failed on ${obj}")
  endif()
  string(REPLACE "\n" ";" lines "${syms}")
  foreach(line IN LISTS lines)
    if(line MATCHES " [WVu] " AND NOT line MATCHES "cr::simd::(avx512|avx2|sse4)::" AND NOT line MATCHES "DW\\.ref\\.")
      message(FATAL_ERROR "CheckIsaSymbols: ${obj} defines a weak symbol outside its ISA namespace:\n  ${line}")
    endif()
  endforeach()
endforeach()
