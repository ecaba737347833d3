# Warnings as an INTERFACE target linked last by every skelcd target (STYLE.md, Tooling).
add_library(skelcd_warnings INTERFACE)
target_compile_options(skelcd_warnings INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wsign-conversion -Wold-style-cast
  -Wnon-virtual-dtor -Woverloaded-virtual -Wdouble-promotion)
if(SKELCD_WERROR)
  target_compile_options(skelcd_warnings INTERFACE -Werror)
endif()
