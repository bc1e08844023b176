# kdrt_embed_cl(<target> OUTPUT_SOURCE <var> FILES <file>...)
#
# Compiles OpenCL C sources into <target>: generates, at build time, a C++
# source defining kdrt::detail::ocl::kEmbeddedClFiles[] / kEmbeddedClFileCount
# (declared in libkdrt/src/opencl/embedded_cl.h), one entry per file in the
# order given, each file's name (relative to the project root) and its bytes.
# The generated source is added to <target> and its path stored in <var>.
# Editing any listed file regenerates and rebuilds it. Relative paths are taken
# relative to the project root (PROJECT_SOURCE_DIR).
#
# The bytes are written as character-literal arrays by KdrtEmbedClScript.cmake,
# so no file content can end a string literal early and no compiler's
# string-literal length limit applies.
set(_KDRT_EMBED_CL_SCRIPT "${CMAKE_CURRENT_LIST_DIR}/KdrtEmbedClScript.cmake")

function(kdrt_embed_cl target)
  cmake_parse_arguments(PARSE_ARGV 1 ARG "" "OUTPUT_SOURCE" "FILES")
  if(ARG_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR "kdrt_embed_cl: unexpected arguments: ${ARG_UNPARSED_ARGUMENTS}")
  endif()
  if(NOT ARG_FILES)
    message(FATAL_ERROR "kdrt_embed_cl: no FILES given")
  endif()

  set(output "${CMAKE_CURRENT_BINARY_DIR}/kdrt_embedded_cl/${target}_embedded_cl.cpp")
  set(script_args "-DKDRT_EMBED_OUTPUT=${output}")
  set(depends "${_KDRT_EMBED_CL_SCRIPT}")
  set(index 0)
  foreach(file IN LISTS ARG_FILES)
    cmake_path(ABSOLUTE_PATH file BASE_DIRECTORY "${PROJECT_SOURCE_DIR}" NORMALIZE OUTPUT_VARIABLE absolute)
    if(NOT EXISTS "${absolute}")
      message(FATAL_ERROR "kdrt_embed_cl: ${absolute} does not exist")
    endif()
    file(RELATIVE_PATH name "${PROJECT_SOURCE_DIR}" "${absolute}")
    list(APPEND script_args "-DKDRT_EMBED_FILE_${index}=${absolute}" "-DKDRT_EMBED_NAME_${index}=${name}")
    list(APPEND depends "${absolute}")
    math(EXPR index "${index} + 1")
  endforeach()
  list(APPEND script_args "-DKDRT_EMBED_COUNT=${index}")

  add_custom_command(
    OUTPUT "${output}"
    COMMAND "${CMAKE_COMMAND}" ${script_args} -P "${_KDRT_EMBED_CL_SCRIPT}"
    DEPENDS ${depends}
    COMMENT "Embedding ${index} OpenCL C files into ${target}"
    VERBATIM)
  target_sources(${target} PRIVATE "${output}")
  if(ARG_OUTPUT_SOURCE)
    set(${ARG_OUTPUT_SOURCE} "${output}" PARENT_SCOPE)
  endif()
endfunction()
