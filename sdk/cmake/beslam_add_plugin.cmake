# beslam_add_plugin(<target> SOURCES <src>... [LIBRARIES <lib>...] [INCLUDES <dir>...] [SETTINGS <json>...]
#                   [ALSO_PROVIDES <id>...] [NO_INSTALL])
#
# Builds one BE-SLAM plugin library: a MODULE linked against beslam::sdk, with hidden symbols (only the
# two entry points are exported by BESLAM_EXPORT_PLUGINS), --no-undefined so a missing symbol fails at
# link time rather than at load time, and no "lib" prefix. Output goes to BESLAM_PLUGIN_OUTPUT_DIR when
# set (the BE-SLAM tree sets it to build/lib/beslam/plugins), else to <build>/plugins; installs to
# <prefix>/lib/beslam/plugins, where the host looks by default (NO_INSTALL: never, for test fixtures).
# SETTINGS: the plugin's settings files
# (beslam_plugin_settings.cmake has their format), turned at configure time into the header
# "<target>_settings.hpp" with the plugin's `kSettings` (and its options struct, if the file declares it).
# The host opens only the library named after a plugin id (<id>.so): a library that provides plugins
# with other ids lists them in ALSO_PROVIDES, and gets a symlink <id>.so beside it (built and installed).
#
# A plugin uses the SDK alone: at the end of the configure step every plugin's link graph is walked, and a
# plugin that links a host library (a target defined under the folder in the global property
# BESLAM_HOST_SOURCE_DIR, which the BE-SLAM tree sets to platform/), directly or through another library,
# stops the configure with an error naming both.
include(${CMAKE_CURRENT_LIST_DIR}/beslam_plugin_settings.cmake)

function(beslam_add_plugin target)
  cmake_parse_arguments(P "NO_INSTALL" "" "SOURCES;LIBRARIES;INCLUDES;SETTINGS;ALSO_PROVIDES" ${ARGN})
  if(NOT P_SOURCES)
    message(FATAL_ERROR "beslam_add_plugin(${target}): SOURCES is required")
  endif()
  add_library(${target} MODULE ${P_SOURCES})
  target_link_libraries(${target} PRIVATE beslam::sdk ${P_LIBRARIES})
  if(P_INCLUDES)
    target_include_directories(${target} PRIVATE ${P_INCLUDES})
  endif()
  if(P_SETTINGS)
    set(generated ${CMAKE_CURRENT_BINARY_DIR}/${target}_settings)
    beslam_plugin_settings(${target} ${generated}/${target}_settings.hpp ${P_SETTINGS})
    target_include_directories(${target} PRIVATE ${generated})
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
  if(NOT ((BESLAM_SANITIZE OR BESLAM_TSAN) AND CMAKE_CXX_COMPILER_ID MATCHES "Clang"))
    target_link_options(${target} PRIVATE -Wl,--no-undefined)
  endif()
  set_property(GLOBAL APPEND PROPERTY BESLAM_ALL_PLUGINS ${target})
  get_property(deferred GLOBAL PROPERTY BESLAM_PLUGIN_CHECK_DEFERRED)
  if(NOT deferred)
    set_property(GLOBAL PROPERTY BESLAM_PLUGIN_CHECK_DEFERRED ON)
    cmake_language(DEFER DIRECTORY ${CMAKE_SOURCE_DIR} CALL beslam_check_plugin_links)
  endif()
  include(GNUInstallDirs)
  if(NOT P_NO_INSTALL)
    install(TARGETS ${target} LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}/beslam/plugins)
  endif()
  foreach(id IN LISTS P_ALSO_PROVIDES)
    add_custom_command(TARGET ${target} POST_BUILD
      COMMAND ${CMAKE_COMMAND} -E create_symlink $<TARGET_FILE_NAME:${target}> ${out}/${id}.so VERBATIM)
    if(NOT P_NO_INSTALL)
      install(CODE "execute_process(COMMAND \${CMAKE_COMMAND} -E create_symlink $<TARGET_FILE_NAME:${target}>
        \"\$ENV{DESTDIR}\${CMAKE_INSTALL_PREFIX}/${CMAKE_INSTALL_LIBDIR}/beslam/plugins/${id}.so\")")
    endif()
  endforeach()
endfunction()

# The names a link item stands for: generator expressions a target's link properties carry ($<LINK_ONLY:x>,
# $<BUILD_INTERFACE:x>) unwrapped, CMake's own markers (::@...) and anything that is not a target dropped.
function(_beslam_link_targets out item_list)
  set(found "")
  foreach(item IN LISTS item_list)
    string(REGEX REPLACE "^\\$<(LINK_ONLY|BUILD_INTERFACE):(.*)>$" "\\2" item "${item}")
    if(item MATCHES "^::@" OR item MATCHES "^\\$<" OR NOT TARGET "${item}")
      continue()
    endif()
    get_target_property(aliased "${item}" ALIASED_TARGET)
    if(aliased)
      set(item ${aliased})
    endif()
    list(APPEND found ${item})
  endforeach()
  set(${out} ${found} PARENT_SCOPE)
endfunction()

function(beslam_check_plugin_links)
  get_property(host_dir GLOBAL PROPERTY BESLAM_HOST_SOURCE_DIR)
  get_property(plugins GLOBAL PROPERTY BESLAM_ALL_PLUGINS)
  if(NOT host_dir)
    return()
  endif()
  foreach(plugin IN LISTS plugins)
    set(queue ${plugin})
    set(seen ${plugin})
    set(via_${plugin} "")
    while(queue)
      list(POP_FRONT queue current)
      get_target_property(imported ${current} IMPORTED)
      if(imported)
        continue()
      endif()
      get_target_property(dir ${current} SOURCE_DIR)
      string(FIND "${dir}/" "${host_dir}/" at)
      if(at EQUAL 0)
        message(FATAL_ERROR "plugin '${plugin}' links the host library '${current}'${via_${current}}: a plugin may "
                            "use only the SDK (beslam::sdk, beslam::formats) and its own libraries; move what it "
                            "needs into sdk/ (docs/writing-a-plugin.md)")
      endif()
      get_target_property(type ${current} TYPE)
      set(items "")
      if(NOT type STREQUAL "INTERFACE_LIBRARY")
        get_target_property(direct ${current} LINK_LIBRARIES)
        if(direct)
          list(APPEND items ${direct})
        endif()
      endif()
      get_target_property(iface ${current} INTERFACE_LINK_LIBRARIES)
      if(iface)
        list(APPEND items ${iface})
      endif()
      _beslam_link_targets(next "${items}")
      foreach(n IN LISTS next)
        if(NOT n IN_LIST seen)
          list(APPEND seen ${n})
          list(APPEND queue ${n})
          if(current STREQUAL plugin)
            set(via_${n} "")
          else()
            set(via_${n} " (through '${current}')")
          endif()
        endif()
      endforeach()
    endwhile()
  endforeach()
endfunction()
