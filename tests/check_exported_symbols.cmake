# ctest driver: libkdrt.so exports kdrt:: and nothing else.
#
# cmake -DLIBRARY=<libkdrt.so> [-DNM=<nm>] -P check_exported_symbols.cmake
#
# Lists the defined dynamic symbols (nm -D --defined-only, demangled) and
# fails on any that is not one of the allowed forms below, and when an
# entry point every user needs is missing (a library that exports nothing
# would pass the first check).
cmake_minimum_required(VERSION 3.25)
foreach(var LIBRARY)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "${var} not set")
  endif()
endforeach()
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
  "kdrt::load_scene(std::filesystem::__cxx11::path const&)"
  "kdrt::Scene::add_sphere("
  "kdrt::to_string(kdrt::ErrorCode)"
  "typeinfo for kdrt::Error")

execute_process(COMMAND "${NM}" -D --defined-only --demangle "${LIBRARY}"
  RESULT_VARIABLE rc OUTPUT_VARIABLE listing ERROR_VARIABLE errors)
if(rc)
  message(FATAL_ERROR "${NM} -D --defined-only ${LIBRARY} failed: ${errors}")
endif()
# One symbol a line: "<address> <type> <demangled name>". Names hold ';'
# (never) and '[' (abi tags): escape the list separator before splitting.
string(REPLACE ";" "\\;" listing "${listing}")
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
