# aia_module(NAME DEPS ... [PRIVATE_DEPS ...]): one static library per module,
# built from src/NAME/*.cc with public headers in include/aia/NAME/. DEPS are
# the libraries its public headers use (passed on to its consumers);
# PRIVATE_DEPS those only its sources use (yaml-cpp, OpenCV's image codecs,
# OSMesa, JSON, libtorch), so that they do not leak into every module
# above. The allowed links are the layering below (also in docs/design.md);
# a link that runs upward is a configure error.
set(AIA_LAYERS_core        "")
set(AIA_LAYERS_estimation  "core")
set(AIA_LAYERS_comm        "core")
set(AIA_LAYERS_scenario    "core;estimation;comm")
set(AIA_LAYERS_world       "core;estimation;comm;scenario")
set(AIA_LAYERS_sim         "core;estimation;comm;scenario;world")
set(AIA_LAYERS_planning    "core;estimation;comm;scenario;world")
set(AIA_LAYERS_learning    "core;estimation;comm;scenario;world;planning")
set(AIA_LAYERS_render      "core;estimation;comm;scenario;world;sim")
set(AIA_LAYERS_runtime     "core;estimation;comm;scenario;world;sim;planning;learning")
set(AIA_LAYERS_commands    "core;estimation;comm;scenario;world;sim;planning;learning;render;runtime")

function(aia_module name)
  cmake_parse_arguments(ARG "" "" "DEPS;PRIVATE_DEPS" ${ARGN})
  if(NOT DEFINED AIA_LAYERS_${name})
    message(FATAL_ERROR "aia_module: unknown module '${name}'")
  endif()
  foreach(dep IN LISTS ARG_DEPS ARG_PRIVATE_DEPS)
    if(dep MATCHES "^aia::(.*)$")
      set(target_module "${CMAKE_MATCH_1}")
      list(FIND AIA_LAYERS_${name} "${target_module}" allowed)
      if(allowed EQUAL -1)
        message(FATAL_ERROR "aia_module: '${name}' may not link '${target_module}' "
                            "(allowed: ${AIA_LAYERS_${name}})")
      endif()
      if(NOT TARGET aia_${target_module})
        message(FATAL_ERROR "aia_module: '${target_module}' must be defined before '${name}'")
      endif()
    endif()
  endforeach()
  file(GLOB sources CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/src/${name}/*.cc)
  add_library(aia_${name} STATIC ${sources})
  add_library(aia::${name} ALIAS aia_${name})
  target_include_directories(aia_${name} PUBLIC
    $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/include>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  # Installed and exported as aia::NAME (find_package(aia), docs/extending.md).
  set_target_properties(aia_${name} PROPERTIES EXPORT_NAME ${name})
  set_property(GLOBAL APPEND PROPERTY AIA_MODULE_TARGETS aia_${name})
  target_link_libraries(aia_${name} PUBLIC ${ARG_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  target_compile_options(aia_${name} PRIVATE -Wall -Wextra)
endfunction()
