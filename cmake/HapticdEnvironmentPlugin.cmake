# hapticd_add_environment_plugin(<name> <source>...)
# The environment plugin <name> (include/hapticd/env/plugin_abi.h,
# docs/environment-plugins.md): the shared object libhapticd-env-<name>.so that a scene's
# [plugin] name = "<name>" loads, with the ABI header (target hapticd::environment_plugin) and
# only its entry symbol exported. Its target is hapticd-env-<name>. Installed with hapticd's
# CMake package (find_package(hapticd)), and used by hapticd's own tests.
function(hapticd_add_environment_plugin name)
  if(NOT name MATCHES "^[a-z0-9][a-z0-9-]*$")
    message(FATAL_ERROR "hapticd_add_environment_plugin(${name}): the name is what a scene's "
                        "[plugin] name says: lower-case letters, digits and '-'")
  endif()
  set(target hapticd-env-${name})
  add_library(${target} MODULE ${ARGN})
  target_link_libraries(${target} PRIVATE hapticd::environment_plugin)
  set_target_properties(${target} PROPERTIES
    C_VISIBILITY_PRESET hidden CXX_VISIBILITY_PRESET hidden VISIBILITY_INLINES_HIDDEN ON)
endfunction()
