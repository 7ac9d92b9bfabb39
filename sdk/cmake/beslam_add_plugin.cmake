# beslam_add_plugin(<target> SOURCES <src>... [LIBRARIES <lib>...] [INCLUDES <dir>...])
#
# Builds one BE-SLAM plugin library: a MODULE linked against beslam::sdk, with hidden symbols (only the
# two entry points are exported by BESLAM_EXPORT_PLUGINS), --no-undefined so a missing symbol fails at
# link time rather than at load time, and no "lib" prefix. Output goes to BESLAM_PLUGIN_OUTPUT_DIR when
# set (the BE-SLAM tree sets it to build/lib/beslam/plugins), else to <build>/plugins; installs to
# <prefix>/lib/beslam/plugins, where the host looks by default.
function(beslam_add_plugin target)
  cmake_parse_arguments(P "" "" "SOURCES;LIBRARIES;INCLUDES" ${ARGN})
  if(NOT P_SOURCES)
    message(FATAL_ERROR "beslam_add_plugin(${target}): SOURCES is required")
  endif()
  add_library(${target} MODULE ${P_SOURCES})
  target_link_libraries(${target} PRIVATE beslam::sdk ${P_LIBRARIES})
  if(P_INCLUDES)
    target_include_directories(${target} PRIVATE ${P_INCLUDES})
  endif()
  if(DEFINED BESLAM_PLUGIN_OUTPUT_DIR)
    set(out ${BESLAM_PLUGIN_OUTPUT_DIR})
  else()
    set(out ${CMAKE_BINARY_DIR}/plugins)
  endif()
  set_target_properties(${target} PROPERTIES
    PREFIX ""
    CXX_VISIBILITY_PRESET hidden
    VISIBILITY_INLINES_HIDDEN ON
    LIBRARY_OUTPUT_DIRECTORY ${out})
  # clang links the sanitizer runtimes into the executable only: a sanitised plugin's references to them
  # resolve at load time, so --no-undefined cannot hold there.
  if(NOT (BESLAM_SANITIZE AND CMAKE_CXX_COMPILER_ID MATCHES "Clang"))
    target_link_options(${target} PRIVATE -Wl,--no-undefined)
  endif()
  set_property(GLOBAL APPEND PROPERTY BESLAM_ALL_PLUGINS ${target})
  include(GNUInstallDirs)
  install(TARGETS ${target} LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}/beslam/plugins)
endfunction()
