# beslam_check_plugin_includes(<source_dir>): no file under <source_dir>/plugins includes a host header.
#
# A plugin's folder (its library, tools/, bench/ and test/) may include the SDK (beslam/sdk/*,
# beslam/formats/*), the interfaces (beslam/*.h), its own and other plugins' headers, the test support
# (beslam/test/*) and third-party headers; never a header of a host module, that is one under
# <source_dir>/platform/<module>/include/beslam/<name>/ or platform/lab/<module>/include/beslam/<name>/
# ("beslam/<name>/..."), nor any path through platform/. The check reads every C/C++ file under plugins/
# and stops with one error that lists each file and the host header it includes.
#
# plugins/CMakeLists.txt runs it at configure time; the test plugins_include_no_host_header runs it again
# as `cmake -DBESLAM_SOURCE_DIR=<dir> -P plugins/check_includes.cmake`, so an include added after the last
# configure fails the suite.
cmake_policy(VERSION 3.16)  # IN_LIST in script mode too

function(beslam_check_plugin_includes source_dir)
  file(GLOB module_dirs LIST_DIRECTORIES true "${source_dir}/platform/*/include/beslam/*"
       "${source_dir}/platform/lab/*/include/beslam/*")
  set(host_names "")
  foreach(dir IN LISTS module_dirs)
    if(IS_DIRECTORY "${dir}")
      get_filename_component(name "${dir}" NAME)
      string(REGEX REPLACE "^${source_dir}/(.*)/include/beslam/[^/]+$" "\\1" module "${dir}")
      list(APPEND host_names ${name})
      set(module_of_${name} ${module})
    endif()
  endforeach()

  file(GLOB_RECURSE sources "${source_dir}/plugins/*.h" "${source_dir}/plugins/*.hh" "${source_dir}/plugins/*.hpp"
       "${source_dir}/plugins/*.c" "${source_dir}/plugins/*.cc" "${source_dir}/plugins/*.cpp")
  list(SORT sources)
  set(found "")
  foreach(file IN LISTS sources)
    file(STRINGS "${file}" lines REGEX "^[ \t]*#[ \t]*include[ \t]*[<\"]")
    file(RELATIVE_PATH relative "${source_dir}" "${file}")
    foreach(line IN LISTS lines)
      if(NOT line MATCHES "^[ \t]*#[ \t]*include[ \t]*[<\"]([^\">]*)[\">]")
        continue()
      endif()
      set(header "${CMAKE_MATCH_1}")
      if(header MATCHES "^beslam/([^/]+)/" AND CMAKE_MATCH_1 IN_LIST host_names)
        string(APPEND found "\n  ${relative} includes ${header} (${module_of_${CMAKE_MATCH_1}})")
      elseif(header MATCHES "(^|/)platform/")
        string(APPEND found "\n  ${relative} includes ${header}")
      endif()
    endforeach()
  endforeach()
  if(found)
    message(FATAL_ERROR "a file under plugins/ includes a host header:${found}\n"
                        "A plugin's folder (library, tools, benchmarks, tests) may include only the SDK "
                        "(beslam/sdk, beslam/formats), the interfaces, its own headers and third-party ones: move "
                        "what the file needs into sdk/, or a file that needs the host into tests/integration or "
                        "platform/lab (docs/architecture.md).")
  endif()
endfunction()

if(CMAKE_SCRIPT_MODE_FILE STREQUAL CMAKE_CURRENT_LIST_FILE)
  if(NOT BESLAM_SOURCE_DIR)
    message(FATAL_ERROR "usage: cmake -DBESLAM_SOURCE_DIR=<source tree> -P ${CMAKE_CURRENT_LIST_FILE}")
  endif()
  beslam_check_plugin_includes("${BESLAM_SOURCE_DIR}")
endif()
