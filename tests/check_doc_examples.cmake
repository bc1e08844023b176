# ctest driver: every code block in docs/API.md is a file of docs/examples,
# quoted verbatim (the files are compiled and run by the api_examples test).
#
# cmake -DDOC=<docs/API.md> -DEXAMPLES_DIR=<docs/examples> -P check_doc_examples.cmake
#
# In the document each example is a "<!-- example: NAME.cpp -->" line directly
# followed by a ```cpp fence holding the file's exact text.
cmake_minimum_required(VERSION 3.25)
foreach(var DOC EXAMPLES_DIR)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "${var} not set")
  endif()
endforeach()
file(READ "${DOC}" doc)
get_filename_component(EXAMPLES_DIR "${EXAMPLES_DIR}" ABSOLUTE)

# Occurrences of `needle` in `text`.
function(count_occurrences text needle out)
  set(n 0)
  string(LENGTH "${needle}" needle_length)
  while(TRUE)
    string(FIND "${text}" "${needle}" at)
    if(at EQUAL -1)
      break()
    endif()
    math(EXPR n "${n} + 1")
    math(EXPR at "${at} + ${needle_length}")
    string(SUBSTRING "${text}" ${at} -1 text)
  endwhile()
  set(${out} ${n} PARENT_SCOPE)
endfunction()

file(GLOB examples RELATIVE "${EXAMPLES_DIR}" "${EXAMPLES_DIR}/*.cpp")
list(LENGTH examples example_count)
if(example_count EQUAL 0)
  message(FATAL_ERROR "no examples in ${EXAMPLES_DIR}")
endif()
set(problems "")
foreach(name IN LISTS examples)
  file(READ "${EXAMPLES_DIR}/${name}" code)
  set(opening "<!-- example: ${name} -->\n```cpp\n")
  string(FIND "${doc}" "${opening}" at)
  if(at EQUAL -1)
    string(APPEND problems "  ${name}: not quoted (no \"<!-- example: ${name} -->\" line followed by ```cpp)\n")
    continue()
  endif()
  string(LENGTH "${opening}" opening_length)
  string(LENGTH "${code}" code_length)
  math(EXPR start "${at} + ${opening_length}")
  string(SUBSTRING "${doc}" ${start} ${code_length} quoted)
  math(EXPR end "${start} + ${code_length}")
  string(SUBSTRING "${doc}" ${end} 4 closing)
  if(NOT quoted STREQUAL code OR NOT closing STREQUAL "```\n")
    string(APPEND problems "  ${name}: the quoted block differs from the file (copy the file into the block)\n")
  endif()
endforeach()

# No block without its file: every ```cpp fence is one of the quotes above.
count_occurrences("${doc}" "```cpp" fences)
count_occurrences("${doc}" "<!-- example: " markers)
if(NOT fences EQUAL example_count OR NOT markers EQUAL example_count)
  string(APPEND problems "  ${DOC} has ${fences} C++ blocks and ${markers} example markers for ${example_count} "
                         "files in ${EXAMPLES_DIR}: each block must be one file, quoted once\n")
endif()
if(NOT problems STREQUAL "")
  message(FATAL_ERROR "docs/API.md and docs/examples disagree:\n${problems}")
endif()
message("${example_count} examples quoted verbatim in ${DOC}")
