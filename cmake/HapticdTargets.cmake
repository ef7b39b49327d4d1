# The two target shapes of the device layer and its plugins (docs/architecture.md §5.2).

# hapticd_plugin_linkable_library(<name> <source>...)
# A static library that the device plugins link: position-independent (the plugins are
# shared objects) with its symbols hidden (a plugin exports its entry point only). Gets the
# alias hapticd::<name without hapticd_> and the include directory.
function(hapticd_plugin_linkable_library name)
  add_library(${name} STATIC ${ARGN})
  string(REGEX REPLACE "^hapticd_" "hapticd::" alias ${name})
  add_library(${alias} ALIAS ${name})
  target_include_directories(${name} PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/include>)
  set_target_properties(${name} PROPERTIES
    POSITION_INDEPENDENT_CODE ON CXX_VISIBILITY_PRESET hidden VISIBILITY_INLINES_HIDDEN ON)
endfunction()

# hapticd_device_plugin(<kind> SOURCES <source>... LINK <library>...)
# The device plugin `kind`: the shared object hapticd-device-<kind>.so that load_device("kind")
# dlopen()s (plugin_loader.hpp), built into the build tree's plugin directory and installed
# to the plugin directory. The loader finds the plugins in the build tree, so the loader's
# library depends on each: anything that loads a plugin builds it.
function(hapticd_device_plugin kind)
  cmake_parse_arguments(PARSE_ARGV 1 arg "" "" "SOURCES;LINK")
  set(target hapticd_device_${kind})
  add_library(${target} MODULE ${arg_SOURCES})
  target_link_libraries(${target} PRIVATE ${arg_LINK})
  set_target_properties(${target} PROPERTIES
    PREFIX "" OUTPUT_NAME hapticd-device-${kind}
    LIBRARY_OUTPUT_DIRECTORY ${HAPTICD_PLUGIN_BUILD_DIR}
    CXX_VISIBILITY_PRESET hidden VISIBILITY_INLINES_HIDDEN ON)
  add_dependencies(hapticd_device ${target})
  install(TARGETS ${target} LIBRARY DESTINATION ${HAPTICD_PLUGIN_INSTALL_DIR})
endfunction()
