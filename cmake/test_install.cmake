# CTest script: installs the build into a temporary prefix, then configures, builds and runs
# against it with find_package(rtdenoise): examples/consumer (rtdenoise::rtdenoise alone) with
# OpenEXR and libpng made unfindable, which it must not need, then cmake/io_consumer
# (COMPONENTS io, rtdenoise::rtdenoise_io).
# Then one rendered scene through the installed package three ways, the C API from C
# (examples/c_consumer), the C++ API (examples/consumer) and Python (cmake/python_consumer.py,
# where the module was built): the same result.
#   cmake -DBUILD_DIR=... -DSOURCE_DIR=... -DWORK_DIR=... [-DPYTHON=...] -P test_install.cmake

file(REMOVE_RECURSE "${WORK_DIR}")
execute_process(COMMAND ${CMAKE_COMMAND} --install "${BUILD_DIR}" --prefix "${WORK_DIR}/prefix"
                RESULT_VARIABLE rc OUTPUT_QUIET)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "cmake --install failed (${rc})")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} -S "${SOURCE_DIR}/examples/consumer"
                        -B "${WORK_DIR}/consumer" -G Ninja
                        -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix
                        -DCMAKE_CXX_COMPILER=${CXX_COMPILER}
                        "-DCMAKE_CXX_FLAGS=${CXX_FLAGS}"  # the sanitizers of a debug build
                        -DCMAKE_DISABLE_FIND_PACKAGE_OpenEXR=ON -DCMAKE_DISABLE_FIND_PACKAGE_PNG=ON
                        --no-warn-unused-cli  # unused they are: the config never looks for them
                RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "configuring the consumer with find_package(rtdenoise) failed "
                      "(with OpenEXR and libpng unfindable: the denoiser must not need them)")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build "${WORK_DIR}/consumer" RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "building the consumer failed")
endif()
execute_process(COMMAND "${WORK_DIR}/consumer/consumer" RESULT_VARIABLE rc
                OUTPUT_VARIABLE out)
message(STATUS "${out}")
if(NOT rc EQUAL 0 OR NOT out MATCHES "mean in 0\\.5[0-9]* out 0\\.5")
  message(FATAL_ERROR "the consumer failed or printed an unexpected mean: ${out}")
endif()

execute_process(COMMAND ${CMAKE_COMMAND} -S "${SOURCE_DIR}/cmake/io_consumer"
                        -B "${WORK_DIR}/io_consumer" -G Ninja
                        -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix
                        -DCMAKE_CXX_COMPILER=${CXX_COMPILER}
                        "-DCMAKE_CXX_FLAGS=${CXX_FLAGS}"
                RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "configuring the io consumer with find_package(rtdenoise COMPONENTS io) failed")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build "${WORK_DIR}/io_consumer" RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "building the io consumer failed")
endif()
execute_process(COMMAND "${WORK_DIR}/io_consumer/io_consumer" "${WORK_DIR}"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out)
message(STATUS "${out}")
if(NOT rc EQUAL 0 OR NOT out MATCHES "^io ok")
  message(FATAL_ERROR "the io consumer failed (${rc}): ${out}")
endif()

# ---- one rendered scene, three languages ----
set(scene "${WORK_DIR}/scene")
set(packs "${WORK_DIR}/packs")
file(MAKE_DIRECTORY "${packs}")
execute_process(COMMAND "${WORK_DIR}/prefix/bin/rtdenoise" render moving-objects -o "${scene}"
                        --width 64 --height 48 --frames 3 --gbuffer-only -q RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the installed rtdenoise render failed (${rc})")
endif()
execute_process(COMMAND "${WORK_DIR}/io_consumer/io_consumer" --pack "${scene}" "${packs}"
                RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "packing the scene's frames as raw buffers failed (${rc})")
endif()
# A sanitizer build's librtdenoise_c needs the sanitizers' C++ runtime, which a C link omits.
set(c_link_flags "")
if(C_FLAGS MATCHES "-fsanitize")
  set(c_link_flags "-DCMAKE_EXE_LINKER_FLAGS=-fsanitize-link-c++-runtime -lstdc++")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} -S "${SOURCE_DIR}/examples/c_consumer"
                        -B "${WORK_DIR}/c_consumer" -G Ninja
                        -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix -DCMAKE_C_COMPILER=${C_COMPILER}
                        "-DCMAKE_C_FLAGS=${C_FLAGS}" ${c_link_flags}
                RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "configuring the C consumer with find_package(rtdenoise) failed")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build "${WORK_DIR}/c_consumer" RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "building the C consumer (C99, the C API) failed")
endif()
foreach(consumer c_consumer/c_consumer consumer/consumer)
  execute_process(COMMAND "${WORK_DIR}/${consumer}" "${packs}" 3 RESULT_VARIABLE rc
                  OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message(STATUS "${out}${err}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${consumer} failed on the rendered scene (${rc})")
  endif()
endforeach()
file(GLOB_RECURSE python_package "${WORK_DIR}/prefix/*__init__.py")
list(FILTER python_package INCLUDE REGEX "/rtdenoise/__init__\\.py$")
if(PYTHON AND python_package)
  list(GET python_package 0 init)
  get_filename_component(package "${init}" DIRECTORY)
  get_filename_component(site "${package}" DIRECTORY)
  execute_process(COMMAND ${CMAKE_COMMAND} -E env "PYTHONPATH=${site}"
                          "${PYTHON}" "${SOURCE_DIR}/cmake/python_consumer.py" "${scene}" "${packs}"
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message(STATUS "${out}${err}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "the installed Python module's result differs or it failed (${rc})")
  endif()
else()  # no Python module built: C against C++ alone, bit for bit
  foreach(i 0 1 2)
    file(SHA256 "${packs}/c_result_${i}.raw" c_hash)
    file(SHA256 "${packs}/cpp_result_${i}.raw" cpp_hash)
    if(NOT c_hash STREQUAL cpp_hash)
      message(FATAL_ERROR "frame ${i}: the C consumer's result differs from the C++ one's")
    endif()
  endforeach()
  message(STATUS "C and C++ results identical (no Python module installed to compare)")
endif()
file(REMOVE_RECURSE "${WORK_DIR}")
