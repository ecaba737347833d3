# cmake -DROOT=<repository> -DDIRS="tools/engine|tools/io" -DFORBID="CLI|nlohmann|tools/cli" -P this
# Fails when a C++ file under DIRS includes a header under one of the FORBID folders: the engine
# and io of tools/ hold no command line and no JSON (<CLI/…>, <nlohmann/…>), and each folder of
# tools/ includes only those below it (docs/architecture.md). The tests tools.layering.* run it.
string(REPLACE "|" ";" FORBID "${FORBID}")
string(REPLACE "|" ";" DIRS "${DIRS}")
string(JOIN "|" alternatives ${FORBID})
set(offending)
foreach(dir IN LISTS DIRS)
  file(GLOB_RECURSE files "${ROOT}/${dir}/*.hpp" "${ROOT}/${dir}/*.cpp" "${ROOT}/${dir}/*.h")
  foreach(file IN LISTS files)
    file(STRINGS "${file}" hits REGEX "^[ \t]*#[ \t]*include[ \t]*[<\"](${alternatives})/")
    foreach(hit IN LISTS hits)
      file(RELATIVE_PATH rel "${ROOT}" "${file}")
      string(STRIP "${hit}" hit)
      list(APPEND offending "${rel}: ${hit}")
    endforeach()
  endforeach()
endforeach()
if(offending)
  list(JOIN offending "\n  " lines)
  message(FATAL_ERROR "${DIRS} must not include ${FORBID} (docs/architecture.md, tools/):\n  ${lines}")
endif()
message(STATUS "no C++ file under ${DIRS} includes ${FORBID}")
