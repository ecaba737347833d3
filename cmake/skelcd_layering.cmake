# Layering rules of tools/ (docs/architecture.md, "tools/"): the engine and io targets link neither
# CLI11 nor nlohmann_json, directly or through anything they link.
#   skelcd_forbid_links(TARGETS skelcd_engine skelcd_io FORBID CLI11::CLI11 nlohmann_json::nlohmann_json)
# checks at the end of configuration (so that links added later by any directory count) and stops
# it with FATAL_ERROR naming the path through which a forbidden library comes in. The sources'
# includes are checked by the tests tools.layering.* (cmake/skelcd_check_includes.cmake).

# The targets (real names, aliases resolved) that `item` names in a link list, or nothing.
function(_skelcd_link_item_targets item out)
  set(result)
  # $<LINK_LIBRARY:WHOLE_ARCHIVE,a,b> and similar: the targets are the comma-separated tail.
  string(REGEX REPLACE "^\\$<[A-Z_]+:([^>]*)>$" "\\1" inner "${item}")
  string(REPLACE "," ";" parts "${inner}")
  foreach(part IN LISTS parts)
    string(REGEX REPLACE "^::@\\([^)]*\\)" "" part "${part}")  # a directory-scoped link item
    if(TARGET "${part}")
      get_target_property(aliased "${part}" ALIASED_TARGET)
      if(aliased)
        list(APPEND result "${aliased}")
      else()
        list(APPEND result "${part}")
      endif()
    endif()
  endforeach()
  set(${out} "${result}" PARENT_SCOPE)
endfunction()

function(_skelcd_check_links target forbidden)
  set(real_forbidden)
  foreach(f IN LISTS forbidden)
    _skelcd_link_item_targets("${f}" resolved)
    list(APPEND real_forbidden ${f} ${resolved})
  endforeach()
  set(queue "${target}")
  set(path_${target} "${target}")
  set(seen)
  while(queue)
    list(POP_FRONT queue current)
    if(current IN_LIST seen)
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
      _skelcd_link_item_targets("${item}" targets)
      foreach(t IN LISTS targets)
        if(t IN_LIST real_forbidden)
          message(FATAL_ERROR
            "${target} must not link ${t} (docs/architecture.md: no CLI11 and no JSON in tools/engine "
            "and tools/io); it comes in through ${path_${current}} -> ${t}")
        endif()
        if(NOT DEFINED path_${t})
          set(path_${t} "${path_${current}} -> ${t}")
        endif()
        list(APPEND queue "${t}")
      endforeach()
    endforeach()
  endwhile()
endfunction()

function(skelcd_forbid_links)
  cmake_parse_arguments(ARG "" "" "TARGETS;FORBID" ${ARGN})
  foreach(target IN LISTS ARG_TARGETS)
    cmake_language(EVAL CODE "
      cmake_language(DEFER DIRECTORY \"${PROJECT_SOURCE_DIR}\" CALL
        _skelcd_check_links \"${target}\" \"${ARG_FORBID}\")")
  endforeach()
endfunction()
