# Layering rules of tools/ (docs/architecture.md, "tools/"): the engine and io targets link neither
# CLI11 nor nlohmann_json, directly or through anything they link.
#   skelcd_forbid_links(TARGETS skelcd_engine skelcd_io FORBID CLI11::CLI11 nlohmann_json::nlohmann_json)
# checks at the end of configuration (so that links added later by any directory count) and stops
# it with FATAL_ERROR naming the path through which a forbidden library comes in. The sources'
# includes are checked by the tests tools.layering.* (cmake/skelcd_check_includes.cmake).

# The names that link item `item` holds: itself, or the comma-separated targets inside a generator
# expression such as $<LINK_ONLY:a> or $<LINK_LIBRARY:WHOLE_ARCHIVE,a>; an alias also gives the
# target it stands for. Names need not be targets in the calling directory (an imported target is
# visible only where it was found), so callers compare names too.
function(_skelcd_link_item_names item out)
  set(result)
  string(REGEX REPLACE "^\\$<[A-Z_]+:([^>]*)>$" "\\1" inner "${item}")
  string(REPLACE "," ";" parts "${inner}")
  foreach(part IN LISTS parts)
    if(part STREQUAL "" OR part MATCHES "^::@")  # ::@(dir) markers of a link from another folder
      continue()
    endif()
    list(APPEND result "${part}")
    if(TARGET "${part}")
      get_target_property(aliased "${part}" ALIASED_TARGET)
      if(aliased)
        list(APPEND result "${aliased}")
      endif()
    endif()
  endforeach()
  set(${out} "${result}" PARENT_SCOPE)
endfunction()

function(_skelcd_check_links target forbidden)
  set(queue "${target}")
  set(path_${target} "${target}")
  set(seen)
  while(queue)
    list(POP_FRONT queue current)
    if(current IN_LIST seen OR NOT TARGET "${current}")
      continue()
    endif()
    list(APPEND seen "${current}")
    set(links)
    get_target_property(type "${current}" TYPE)
    if(NOT type STREQUAL "INTERFACE_LIBRARY")
      get_target_property(direct "${current}" LINK_LIBRARIES)
      if(direct)
        list(APPEND links ${direct})
      endif()
    endif()
    get_target_property(interface "${current}" INTERFACE_LINK_LIBRARIES)
    if(interface)
      list(APPEND links ${interface})
    endif()
    foreach(item IN LISTS links)
      _skelcd_link_item_names("${item}" names)
      foreach(name IN LISTS names)
        if(name IN_LIST forbidden)
          message(FATAL_ERROR
            "${target} must not link ${name} (docs/architecture.md: no CLI11 and no JSON in "
            "tools/engine and tools/io); it comes in through ${path_${current}} -> ${name}")
        endif()
        if(NOT DEFINED path_${name})
          set(path_${name} "${path_${current}} -> ${name}")
        endif()
        list(APPEND queue "${name}")
      endforeach()
    endforeach()
  endwhile()
endfunction()

function(skelcd_forbid_links)
  cmake_parse_arguments(ARG "" "" "TARGETS;FORBID" ${ARGN})
  # Resolved here, where the forbidden targets are found, with whatever they are aliases of.
  set(forbidden)
  foreach(f IN LISTS ARG_FORBID)
    _skelcd_link_item_names("${f}" names)
    list(APPEND forbidden ${names})
  endforeach()
  foreach(target IN LISTS ARG_TARGETS)
    cmake_language(EVAL CODE "
      cmake_language(DEFER DIRECTORY \"${PROJECT_SOURCE_DIR}\" CALL
        _skelcd_check_links \"${target}\" \"${forbidden}\")")
  endforeach()
endfunction()
