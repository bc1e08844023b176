# ctest driver: libkdrt.so exports kdrt:: and nothing else.
#
# cmake -DLIBRARY=<libkdrt.so> [-DINCLUDE_DIR=<libkdrt/include/kdrt>] [-DNM=<nm>] -P check_exported_symbols.cmake
#
# Lists the defined dynamic symbols (nm -D --defined-only, demangled) and
# fails on any that is not one of the allowed forms below, and when an
# entry point every user needs is missing (a library that exports nothing
# would pass the first check). With INCLUDE_DIR, also fails on a free
# function declared in the public headers without KDRT_API (one that
# users of libkdrt.so could not link).
cmake_minimum_required(VERSION 3.25)
foreach(var LIBRARY)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "${var} not set")
  endif()
endforeach()
if(INCLUDE_DIR)
  # The headers' style: declarations start in column 0, continuation lines are indented.
  get_filename_component(INCLUDE_DIR "${INCLUDE_DIR}" ABSOLUTE)
  file(GLOB headers "${INCLUDE_DIR}/*.h")
  if(NOT headers)
    message(FATAL_ERROR "no headers in ${INCLUDE_DIR}")
  endif()
  set(unexported "")
  foreach(header IN LISTS headers)
    file(READ "${header}" text)
    # One list item a line: ';' and unbalanced brackets would split or join items.
    string(REPLACE ";" "<semicolon>" text "${text}")
    string(REPLACE "[" "<opening>" text "${text}")
    string(REPLACE "]" "<closing>" text "${text}")
    string(REPLACE "\n" ";" header_lines "${text}")
    set(number 0)
    set(previous "")
    foreach(line IN LISTS header_lines)
      math(EXPR number "${number} + 1")
      # A template defined in the header (the line after `template <...>`) is
      # instantiated in the caller: nothing to export.
      set(after_template FALSE)
      if(previous MATCHES "^template")
        set(after_template TRUE)
      endif()
      set(previous "${line}")
      if(NOT after_template AND line MATCHES "^[A-Za-z_]" AND line MATCHES "\\("
         AND NOT line MATCHES "^(KDRT_API |inline |return |typedef |struct |class |enum |namespace |using |static_assert|template|extern )")
        get_filename_component(name "${header}" NAME)
        string(REPLACE "<semicolon>" ";" line "${line}")
        string(REPLACE "<opening>" "[" line "${line}")
        string(REPLACE "<closing>" "]" line "${line}")
        string(APPEND unexported "  ${name}:${number}: ${line}\n")
      endif()
    endforeach()
  endforeach()
  if(NOT unexported STREQUAL "")
    message(FATAL_ERROR "public functions declared without KDRT_API (kdrt/export.h):\n${unexported}")
  endif()
endif()

if(NOT NM)
  find_program(NM NAMES nm REQUIRED)
endif()

# Allowed demangled names, each with its reason.
set(allowed
  # The API itself: functions, member functions and constants in namespace kdrt.
  "^kdrt::"
  # typeinfo of exported polymorphic classes: catching kdrt::Error thrown by the
  # library (and dynamic_cast) compares typeinfo across the library boundary.
  "^typeinfo for kdrt::"
  "^typeinfo name for kdrt::"
  # vtables of exported polymorphic classes (kdrt::Error), constructed inline by users.
  "^vtable for kdrt::")
# What any user of the library links against.
set(required
  "kdrt::render(kdrt::Scene const&, kdrt::RenderOptions const&)"
  "kdrt::CommittedScene::commit(kdrt::Device const&, kdrt::Scene const&, kdrt::CommitOptions const&)"
  "kdrt::CommittedScene::render(kdrt::FrameOptions const&) const"
  "kdrt::load_scene(std::filesystem::__cxx11::path const&, kdrt::SceneLoadOptions const&)"
  "kdrt::Scene::add_sphere("
  "kdrt::to_string(kdrt::ErrorCode)"
  "typeinfo for kdrt::Error")

execute_process(COMMAND "${NM}" -D --defined-only --demangle "${LIBRARY}"
  RESULT_VARIABLE rc OUTPUT_VARIABLE listing ERROR_VARIABLE errors)
if(rc)
  message(FATAL_ERROR "${NM} -D --defined-only ${LIBRARY} failed: ${errors}")
endif()
# One symbol a line: "<address> <type> <demangled name>"; brackets (abi tags,
# operator[]) are set aside so that they cannot join list items.
string(REPLACE ";" "<semicolon>" listing "${listing}")
string(REPLACE "[" "<opening>" listing "${listing}")
string(REPLACE "]" "<closing>" listing "${listing}")
string(REPLACE "\n" ";" lines "${listing}")
set(count 0)
set(bad "")
set(names "")
foreach(line IN LISTS lines)
  if(line STREQUAL "")
    continue()
  endif()
  if(NOT line MATCHES "^[0-9a-fA-F]+ [A-Za-z] (.+)$")
    message(FATAL_ERROR "unexpected nm output line: ${line}")
  endif()
  set(name "${CMAKE_MATCH_1}")
  string(REPLACE "<semicolon>" ";" name "${name}")
  string(REPLACE "<opening>" "[" name "${name}")
  string(REPLACE "<closing>" "]" name "${name}")
  math(EXPR count "${count} + 1")
  string(APPEND names "${name}\n")
  set(ok FALSE)
  foreach(pattern IN LISTS allowed)
    if(name MATCHES "${pattern}")
      set(ok TRUE)
      break()
    endif()
  endforeach()
  if(NOT ok)
    string(APPEND bad "  ${name}\n")
  endif()
endforeach()
if(NOT bad STREQUAL "")
  message(FATAL_ERROR "${LIBRARY} exports symbols outside namespace kdrt "
                      "(missing KDRT_API hygiene or libkdrt/kdrt.map):\n${bad}")
endif()
set(missing "")
foreach(symbol IN LISTS required)
  string(FIND "${names}" "${symbol}" at)
  if(at EQUAL -1)
    string(APPEND missing "  ${symbol}\n")
  endif()
endforeach()
if(NOT missing STREQUAL "")
  message(FATAL_ERROR "${LIBRARY} does not export (KDRT_API missing?):\n${missing}")
endif()
message("${count} exported symbols, all in namespace kdrt")
