# `cmake --install`: the public headers, the static libraries and a CMake package, so that a game
# writes `find_package(Weft REQUIRED)` and links `Weft::weft` (examples/README.md).
#
#   <prefix>/include/weft/...                 headers (whole folders, so new headers are installed too)
#   <prefix>/lib/libweft.a, libweft_cuda.a …  the libraries that were built
#   <prefix>/lib/cmake/Weft/                  WeftConfig.cmake, WeftConfigVersion.cmake and one
#                                             Weft<Component>Targets.cmake per component
#
# One export set per component: a program that uses only Weft::weft needs neither CUDA nor Vulkan
# installed, and WeftConfig.cmake loads a component only when its dependencies are found.
include(CMakePackageConfigHelpers)

set(WEFT_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/Weft CACHE STRING
    "Where `cmake --install` puts WeftConfig.cmake, relative to the prefix")
mark_as_advanced(WEFT_INSTALL_CMAKEDIR)

# weft_install_component(COMPONENT TARGET HEADER_DIR): installs TARGET (export name Weft::COMPONENT),
# its headers (the tree under HEADER_DIR/weft) and its targets file: WeftTargets.cmake for the core,
# Weft<Component>Targets.cmake (WeftCudaTargets.cmake, …) for the others, as WeftConfig.cmake expects.
function(weft_install_component component target header_dir)
  if(component STREQUAL "weft")
    set(export_set WeftTargets)
  else()
    string(SUBSTRING ${component} 0 1 first)
    string(TOUPPER ${first} first)
    string(SUBSTRING ${component} 1 -1 rest)
    set(export_set Weft${first}${rest}Targets)
  endif()
  if(WEFT_SANITIZE)
    # Instrumented archives need the sanitizer runtimes at the program's link (the build tree gets
    # them from weft_warnings, which is not installed).
    target_link_options(${target} INTERFACE $<INSTALL_INTERFACE:-fsanitize=${WEFT_SANITIZE}>)
  endif()
  install(TARGETS ${target} EXPORT ${export_set}
          ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
          LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
          RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  install(DIRECTORY ${header_dir}/weft DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
          FILES_MATCHING PATTERN "*.h" PATTERN "*.hpp" PATTERN "*.cuh")
  install(EXPORT ${export_set} NAMESPACE Weft:: DESTINATION ${WEFT_INSTALL_CMAKEDIR})
  set_property(GLOBAL APPEND PROPERTY WEFT_INSTALLED_COMPONENTS ${component})
endfunction()

weft_install_component(weft weft ${PROJECT_SOURCE_DIR}/runtime/include)
if(TARGET weft_cuda)
  weft_install_component(cuda weft_cuda ${PROJECT_SOURCE_DIR}/cuda/include)
endif()
if(TARGET weft_render)
  weft_install_component(render weft_render ${PROJECT_SOURCE_DIR}/render/include)
endif()
if(TARGET weft_assets)
  weft_install_component(assets weft_assets ${PROJECT_SOURCE_DIR}/assets/include)
endif()

get_property(WEFT_INSTALLED_COMPONENTS GLOBAL PROPERTY WEFT_INSTALLED_COMPONENTS)
configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/WeftConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/cmake/WeftConfig.cmake
                              INSTALL_DESTINATION ${WEFT_INSTALL_CMAKEDIR})
# 0.x: a minor release may change the API, so only the same major.minor satisfies a request.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/cmake/WeftConfigVersion.cmake
                                 VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/cmake/WeftConfig.cmake ${PROJECT_BINARY_DIR}/cmake/WeftConfigVersion.cmake
        DESTINATION ${WEFT_INSTALL_CMAKEDIR})
# Weft's own assets a program may load: the rigged character (tools/make_character.py), which
# Weft_DATA_DIR (WeftConfig.cmake) points programs such as examples/cape_runner to.
install(FILES ${PROJECT_SOURCE_DIR}/assets/characters/runner.gltf DESTINATION ${CMAKE_INSTALL_DATADIR}/weft/characters)
