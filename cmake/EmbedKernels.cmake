# Embeds the OpenCL C sources into the binary as one string, so that kernels are
# never loaded from a path relative to the working directory.
#
# cellray_embed_kernels(<out.cpp> <symbol> <file>...) concatenates the files in
# the order given, each preceded by `#line 1 "kernels/<name>"` so that compiler
# messages name the real file, and comments out `#include "..."` of sibling
# files (they are part of the concatenation already).
function(cellray_embed_kernels out symbol)
  set(files ${ARGN})
  add_custom_command(
    OUTPUT ${out}
    COMMAND ${CMAKE_COMMAND} -DOUT=${out} -DSYMBOL=${symbol} "-DFILES=${files}"
            -P ${PROJECT_SOURCE_DIR}/cmake/EmbedKernelsScript.cmake
    DEPENDS ${files} ${PROJECT_SOURCE_DIR}/cmake/EmbedKernelsScript.cmake
    COMMENT "Embedding OpenCL sources into ${symbol}"
    VERBATIM)
endfunction()
