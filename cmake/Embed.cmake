# overtake_embed(TARGET <lib> [ALIAS <alias>] NAMESPACE <ns> FILES <name>=<path> ...)
# Builds a static library that holds the files' bytes, looked up by name at run time
# through `std::optional<std::string_view> <ns>::embedded_file(std::string_view name)`.
# ALIAS names the library's alias target (e.g. overtake::resources).
function(overtake_embed)
  cmake_parse_arguments(ARG "" "TARGET;ALIAS;NAMESPACE" "FILES" ${ARGN})
  set(out "${CMAKE_CURRENT_BINARY_DIR}/${ARG_TARGET}_embedded.cpp")
  set(paths "")
  set(spec "")
  foreach(entry IN LISTS ARG_FILES)
    string(FIND "${entry}" "=" eq)
    string(SUBSTRING "${entry}" 0 ${eq} name)
    math(EXPR start "${eq} + 1")
    string(SUBSTRING "${entry}" ${start} -1 path)
    list(APPEND paths "${path}")
    list(APPEND spec "${name}=${path}")
  endforeach()
  string(REPLACE ";" "|" spec_arg "${spec}")
  add_custom_command(
    OUTPUT "${out}"
    COMMAND ${CMAKE_COMMAND} "-DOUT=${out}" "-DNAMESPACE=${ARG_NAMESPACE}"
            "-DSPEC=${spec_arg}" -P "${PROJECT_SOURCE_DIR}/cmake/embed_files.cmake"
    DEPENDS ${paths} "${PROJECT_SOURCE_DIR}/cmake/embed_files.cmake"
    COMMENT "Embedding ${ARG_TARGET} resources"
    VERBATIM)
  add_library(${ARG_TARGET} STATIC "${out}")
  if(ARG_ALIAS)
    add_library(${ARG_ALIAS} ALIAS ${ARG_TARGET})
  endif()
  target_compile_features(${ARG_TARGET} PUBLIC cxx_std_20)
endfunction()
