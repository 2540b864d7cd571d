# Installs the current build into a scratch prefix, builds examples/hello_cloth as a project of its
# own against it (find_package(Weft REQUIRED) through CMAKE_PREFIX_PATH) and checks that it prints
# the same tip position as the hello_cloth built inside the tree, both on the CPU backend.
#   cmake -DBUILD_DIR=… -DEXAMPLE_DIR=… -DWORK_DIR=… -DIN_TREE_EXE=… -DGENERATOR=… -DMAKE_PROGRAM=…
#         -DCXX_COMPILER=… [-DCXX_COMPILER_LAUNCHER=…] [-DBUILD_TYPE=…] [-DCUDA_ROOT=…] [-DRUNNER_DIR=…]
#         -P find_package_example.cmake
foreach(var BUILD_DIR EXAMPLE_DIR WORK_DIR IN_TREE_EXE GENERATOR CXX_COMPILER)
  if(NOT ${var})
    message(FATAL_ERROR "find_package_example.cmake: -D${var}=… is required")
  endif()
endforeach()

# run(STEP <what it checks> COMMAND …): runs a step, shows its output, stops with a message naming it.
function(run step)
  cmake_parse_arguments(ARG "" "OUTPUT" "COMMAND" ${ARGN})
  string(JOIN " " shown ${ARG_COMMAND})
  message("== ${step}\n$ ${shown}")
  execute_process(COMMAND ${ARG_COMMAND} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message("${out}${err}")
  if(NOT rc STREQUAL "0")
    message(FATAL_ERROR "FAILED: ${step} (exit code ${rc}); its output is above")
  endif()
  if(ARG_OUTPUT)
    set(${ARG_OUTPUT} "${out}" PARENT_SCOPE)
  endif()
endfunction()

# tip_of(OUTPUT_TEXT VAR WHO): the "x y z" of hello_cloth's tip line, or a failure naming WHO.
function(tip_of text var who)
  if(NOT text MATCHES "tip position after 120 frames \\(m\\): ([^\n]+)")
    message(FATAL_ERROR "FAILED: ${who} printed no line 'tip position after 120 frames (m): x y z'")
  endif()
  set(${var} "${CMAKE_MATCH_1}" PARENT_SCOPE)
endfunction()

set(prefix ${WORK_DIR}/prefix)
set(example_build ${WORK_DIR}/hello_cloth)
file(REMOVE_RECURSE ${WORK_DIR})

set(config_arg)
if(BUILD_TYPE)
  set(config_arg --config ${BUILD_TYPE})
endif()
run("cmake --install of the build into a scratch prefix"
    COMMAND ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix} ${config_arg})
# The package files sit under the library folder (lib/, or lib/<multiarch>/ under /usr).
file(GLOB_RECURSE package_files RELATIVE ${prefix} ${prefix}/Weft*.cmake)
foreach(file WeftConfig.cmake WeftConfigVersion.cmake WeftTargets.cmake include/weft/world.h)
  if(NOT EXISTS ${prefix}/${file} AND NOT package_files MATCHES "(^|;)[^;]*/${file}(;|$)")
    file(GLOB_RECURSE found RELATIVE ${prefix} ${prefix}/*)
    list(JOIN found "\n  " found)
    message(FATAL_ERROR "FAILED: the install has no ${file}; it holds:\n  ${found}")
  endif()
endforeach()

# The same compiler, generator and build type as the tree; the launcher (ccache) only where the tree used one.
set(configure_args -S ${EXAMPLE_DIR} -B ${example_build} -G ${GENERATOR}
    -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_CXX_COMPILER=${CXX_COMPILER})
if(MAKE_PROGRAM)
  list(APPEND configure_args -DCMAKE_MAKE_PROGRAM=${MAKE_PROGRAM})
endif()
if(CXX_COMPILER_LAUNCHER)
  list(APPEND configure_args -DCMAKE_CXX_COMPILER_LAUNCHER=${CXX_COMPILER_LAUNCHER})
endif()
if(BUILD_TYPE)
  list(APPEND configure_args -DCMAKE_BUILD_TYPE=${BUILD_TYPE})
endif()
if(CUDA_ROOT)
  list(APPEND configure_args -DCUDAToolkit_ROOT=${CUDA_ROOT})
endif()
run("configure examples/hello_cloth alone with find_package(Weft REQUIRED)" COMMAND ${CMAKE_COMMAND} ${configure_args})

# It must have used the scratch install, not a Weft installed elsewhere on the machine.
file(STRINGS ${example_build}/CMakeCache.txt weft_dir REGEX "^Weft_DIR:")
string(REGEX REPLACE "^Weft_DIR:[A-Z]+=" "" weft_dir "${weft_dir}")
file(REAL_PATH "${weft_dir}" weft_dir)
file(REAL_PATH "${prefix}" real_prefix)
string(FIND "${weft_dir}" "${real_prefix}/" at)
if(NOT at EQUAL 0)
  message(FATAL_ERROR "FAILED: find_package(Weft) found '${weft_dir}', not the scratch install under ${real_prefix}")
endif()

run("build the separate hello_cloth project" COMMAND ${CMAKE_COMMAND} --build ${example_build} ${config_arg})
find_program(installed_exe hello_cloth PATHS ${example_build} ${example_build}/${BUILD_TYPE} NO_DEFAULT_PATH)
if(NOT installed_exe)
  message(FATAL_ERROR "FAILED: the separate build made no hello_cloth executable under ${example_build}")
endif()

run("run hello_cloth built against the installed package" COMMAND ${installed_exe} --cpu OUTPUT installed_out)
run("run hello_cloth built inside the tree" COMMAND ${IN_TREE_EXE} --cpu OUTPUT in_tree_out)
tip_of("${installed_out}" installed_tip "the hello_cloth built against the installed package")
tip_of("${in_tree_out}" in_tree_tip "the hello_cloth built inside the tree")
if(NOT installed_tip STREQUAL in_tree_tip)
  message(FATAL_ERROR "FAILED: the tip positions differ (m):\n  installed package: ${installed_tip}\n  inside the tree:   ${in_tree_tip}")
endif()
message("PASSED: both builds put the tip at ${in_tree_tip} m")

# The game prototype (examples/cape_runner) against the same install, where the renderer is in it:
# configured and built alone (it needs a window to run: tests/cli runs the in-tree one under Xvfb).
if(RUNNER_DIR)
  set(runner_build ${WORK_DIR}/cape_runner)
  list(TRANSFORM configure_args REPLACE "^${EXAMPLE_DIR}$" "${RUNNER_DIR}")
  list(TRANSFORM configure_args REPLACE "^${example_build}$" "${runner_build}")
  run("configure examples/cape_runner alone with find_package(Weft REQUIRED COMPONENTS render)" COMMAND ${CMAKE_COMMAND} ${configure_args})
  run("build the separate cape_runner project" COMMAND ${CMAKE_COMMAND} --build ${runner_build} ${config_arg})
  message("PASSED: cape_runner builds against the installed package")
endif()
