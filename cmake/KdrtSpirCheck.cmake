# The spir_strict_compile test: compiles the assembled kernel source as strict
# OpenCL C 1.2 for SPIR with clang, once per option set, warnings as errors.
# Catches what a lenient driver (PoCL, NVIDIA) would accept but another would
# reject, without needing any OpenCL device.
#
# cmake -DDUMP_TOOL=<kdrt_dump_kernel_source> -DSOURCE_FILE=<out.cl> [-DCLANG=<clang-15>]
#       -DKDRT_SPIR_OPTION_COUNT=<n> -DKDRT_SPIR_OPTIONS_<i>="<-D options>" ... -P KdrtSpirCheck.cmake
#
# Without clang-15 the test is skipped: exit code 77 where CMake can set it
# (3.29+), else the output line KDRT_SPIR_SKIPPED (SKIP_REGULAR_EXPRESSION).
cmake_minimum_required(VERSION 3.25)

macro(kdrt_spir_skip why)
  message("KDRT_SPIR_SKIPPED: ${why}")
  if(CMAKE_VERSION VERSION_GREATER_EQUAL 3.29)
    cmake_language(EXIT 77)
  endif()
  return()
endmacro()

foreach(var DUMP_TOOL SOURCE_FILE)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "KdrtSpirCheck: ${var} is not set")
  endif()
endforeach()

if(NOT CLANG OR NOT EXISTS "${CLANG}")
  find_program(KDRT_SPIR_CLANG NAMES clang-15)
  set(CLANG "${KDRT_SPIR_CLANG}")
endif()
if(NOT CLANG)
  kdrt_spir_skip("clang-15 not found")
endif()

# The dump tool also lists every option set the specialisation can produce.
execute_process(COMMAND "${DUMP_TOOL}" "${SOURCE_FILE}" "${SOURCE_FILE}.variants" RESULT_VARIABLE dump_result)
if(NOT dump_result EQUAL 0)
  message(FATAL_ERROR "KdrtSpirCheck: ${DUMP_TOOL} failed (${dump_result})")
endif()

if(UNIX)
  set(object /dev/null)
else()
  set(object "${SOURCE_FILE}.bc")
endif()

# Explicit option sets, then every variant the specialisation produces.
if(NOT DEFINED KDRT_SPIR_OPTION_COUNT)
  set(KDRT_SPIR_OPTION_COUNT 0)
endif()
file(STRINGS "${SOURCE_FILE}.variants" variants)
foreach(v IN LISTS variants)
  set(KDRT_SPIR_OPTIONS_${KDRT_SPIR_OPTION_COUNT} "${v}")
  math(EXPR KDRT_SPIR_OPTION_COUNT "${KDRT_SPIR_OPTION_COUNT} + 1")
endforeach()
if(KDRT_SPIR_OPTION_COUNT LESS 1)
  message(FATAL_ERROR "KdrtSpirCheck: no option sets to compile")
endif()
math(EXPR last "${KDRT_SPIR_OPTION_COUNT} - 1")
set(failed 0)
set(passed 0)
foreach(i RANGE ${last})
  set(option_text "${KDRT_SPIR_OPTIONS_${i}}")
  separate_arguments(options UNIX_COMMAND "${option_text}")
  # -emit-llvm: Debian's clang has no SPIR backend to assemble an object
  # with; the front end and IR generation are what check the source. The
  # front end finds the language errors; IR generation, half of the time,
  # adds few: it runs on every eighth variant (the explicit sets first).
  math(EXPR phase "${i} % 8")
  if(phase EQUAL 0)
    set(stage -emit-llvm -c -o "${object}")
  else()
    set(stage -fsyntax-only)
  endif()
  execute_process(
    COMMAND "${CLANG}" -x cl -cl-std=CL1.2 -target spir64 -Xclang -finclude-default-header
            -Werror -Wall ${options} ${stage} "${SOURCE_FILE}"
    RESULT_VARIABLE result
    OUTPUT_VARIABLE output
    ERROR_VARIABLE output)
  if(result EQUAL 0)
    math(EXPR passed "${passed} + 1")
  else()
    message("FAILED  [${option_text}]\n${output}")
    math(EXPR failed "${failed} + 1")
  endif()
endforeach()

message("${passed} of ${KDRT_SPIR_OPTION_COUNT} kernel variants compile as strict OpenCL C 1.2 for SPIR")
if(failed GREATER 0)
  message(FATAL_ERROR "${failed} of ${KDRT_SPIR_OPTION_COUNT} option sets failed to compile as strict OpenCL C 1.2 "
                      "(${CLANG}; source ${SOURCE_FILE})")
endif()
