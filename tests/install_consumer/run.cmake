# ctest driver: install kdrt into a scratch prefix, then configure, build and
# run the consumer project against it with find_package(kdrt).
#
# cmake -DKDRT_BUILD_DIR=<build> -DCONSUMER_SOURCE_DIR=<this dir> -DWORK_DIR=<scratch>
#       [-DCXX_COMPILER=<c++>] [-DSTATIC=ON]
#       [-DEXAMPLES_DIR=<docs/examples> -DSCENES_DIR=<scenes> [-DDEVICE=<KDRT_DEVICE for them>]]
#       -P run.cmake
#
# Shared (the default): the consumer must not have found any of kdrt's private
# dependencies, and must need libkdrt by its versioned SONAME. With
# EXAMPLES_DIR every example there is built and run, in a directory where
# "scenes/" leads to SCENES_DIR (the examples' default scene paths).
cmake_minimum_required(VERSION 3.25)
foreach(var KDRT_BUILD_DIR CONSUMER_SOURCE_DIR WORK_DIR)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "${var} not set")
  endif()
endforeach()
if(NOT STATIC)
  set(STATIC OFF)
endif()

function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(rc)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}")
  endif()
  set(run_output "${out}" PARENT_SCOPE)
endfunction()

file(REMOVE_RECURSE "${WORK_DIR}")
set(prefix "${WORK_DIR}/prefix")
run("installing kdrt" "${CMAKE_COMMAND}" --install "${KDRT_BUILD_DIR}" --prefix "${prefix}")

set(configure_args -S "${CONSUMER_SOURCE_DIR}" -B "${WORK_DIR}/build" "-DCMAKE_PREFIX_PATH=${prefix}"
                   -DCMAKE_BUILD_TYPE=Release "-DKDRT_CONSUMER_STATIC=${STATIC}")
if(CXX_COMPILER)
  list(APPEND configure_args "-DCMAKE_CXX_COMPILER=${CXX_COMPILER}")
endif()
if(EXAMPLES_DIR)
  list(APPEND configure_args "-DKDRT_EXAMPLES_DIR=${EXAMPLES_DIR}")
endif()
run("configuring the consumer" "${CMAKE_COMMAND}" ${configure_args})
run("building the consumer" "${CMAKE_COMMAND}" --build "${WORK_DIR}/build")

if(NOT STATIC)
  # find_package(kdrt) for the shared library finds glm and Threads, nothing else.
  file(STRINGS "${WORK_DIR}/build/CMakeCache.txt" found
       REGEX "^(OpenCL_[A-Z_]+|nlohmann_json_DIR|TBB_DIR|assimp_DIR|OpenImageIO_[A-Z_]+|xxhash_[A-Z_]+|PNG_[A-Z_]+|PKG_CONFIG_EXECUTABLE)[:=]")
  if(found)
    message(FATAL_ERROR "find_package(kdrt) looked for private dependencies:\n${found}")
  endif()
  # The consumer needs libkdrt by its SONAME, which names the ABI version.
  find_program(OBJDUMP NAMES objdump REQUIRED)
  file(GLOB libraries "${prefix}/lib*/libkdrt.so")
  list(LENGTH libraries n)
  if(NOT n EQUAL 1)
    message(FATAL_ERROR "expected one libkdrt.so under ${prefix}, found: ${libraries}")
  endif()
  run("reading libkdrt.so's headers" "${OBJDUMP}" -p "${libraries}")
  if(NOT run_output MATCHES "SONAME +(libkdrt\\.so\\.[0-9.]+)")
    message(FATAL_ERROR "libkdrt.so has no versioned SONAME:\n${run_output}")
  endif()
  set(soname "${CMAKE_MATCH_1}")
  run("reading the consumer's headers" "${OBJDUMP}" -p "${WORK_DIR}/build/consumer")
  string(FIND "${run_output}" "NEEDED               ${soname}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "the consumer does not need ${soname}:\n${run_output}")
  endif()
  message("libkdrt.so: SONAME ${soname}")
endif()

run("running the consumer" "${WORK_DIR}/build/consumer")
message("${run_output}")

if(EXAMPLES_DIR)
  set(run_dir "${WORK_DIR}/run")
  file(MAKE_DIRECTORY "${run_dir}")
  if(SCENES_DIR)
    file(CREATE_LINK "${SCENES_DIR}" "${run_dir}/scenes" SYMBOLIC)
  endif()
  file(GLOB examples RELATIVE "${EXAMPLES_DIR}" "${EXAMPLES_DIR}/*.cpp")
  list(LENGTH examples n)
  if(n EQUAL 0)
    message(FATAL_ERROR "no examples in ${EXAMPLES_DIR}")
  endif()
  if(DEVICE)
    set(ENV{KDRT_DEVICE} "${DEVICE}")  # Device::open() and render() with no device named
  endif()
  set(failed "")
  foreach(example IN LISTS examples)
    get_filename_component(name "${example}" NAME_WE)
    execute_process(COMMAND "${WORK_DIR}/build/${name}" WORKING_DIRECTORY "${run_dir}" TIMEOUT 300
      RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
    message("== ${name} (exit ${rc})\n${out}")
    if(NOT rc EQUAL 0)
      list(APPEND failed "${name}")
    endif()
  endforeach()
  if(failed)
    message(FATAL_ERROR "examples failed: ${failed}")
  endif()
  message("${n} examples built and ran")
endif()
