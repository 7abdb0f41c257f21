# CTest script: installs the build into a temporary prefix, then configures, builds and runs
# against it with find_package(rtdenoise): examples/consumer (rtdenoise::rtdenoise alone) with
# OpenEXR and libpng made unfindable, which it must not need, then cmake/io_consumer
# (COMPONENTS io, rtdenoise::rtdenoise_io).
#   cmake -DBUILD_DIR=... -DSOURCE_DIR=... -DWORK_DIR=... -P test_install.cmake
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
file(REMOVE_RECURSE "${WORK_DIR}")
