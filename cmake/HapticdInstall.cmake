# What `cmake --install` places besides the executables and plugins (which their own
# CMakeLists.txt install); docs/install.md lists the whole tree.
#
# Everything is placed relative to the prefix of the install, not of the configure, so that
# one build installs to /usr/local (`cmake --install`) and packages for /usr (CPack, with
# CPACK_SET_DESTDIR) alike: the files that name installed paths (the unit, the default
# config) are written at install time by HapticdInstallTime.cmake. systemd and udev read
# lib/systemd/system and lib/udev/rules.d below /usr and below /usr/local.

install(FILES ${PROJECT_SOURCE_DIR}/config/udev/70-hapticd.rules
        DESTINATION ${HAPTICD_UDEV_RULES_INSTALL_DIR})

# Scenes, device models, operator classes and example configs, with their relative paths
# (examples/ name ../scenes/) as in the source tree.
install(DIRECTORY ${PROJECT_SOURCE_DIR}/config/scenes ${PROJECT_SOURCE_DIR}/config/devices
                  ${PROJECT_SOURCE_DIR}/config/operators ${PROJECT_SOURCE_DIR}/config/examples
        DESTINATION ${HAPTICD_DATA_INSTALL_DIR} FILES_MATCHING PATTERN "*.toml")
# The drop-in that binds an instance to its device (docs/install.md, "Started by its device").
install(FILES ${PROJECT_SOURCE_DIR}/config/examples/systemd/bind-to-device.conf
        DESTINATION ${HAPTICD_DATA_INSTALL_DIR}/examples/systemd)

# The group of the control sockets (config/sysusers/hapticd.conf).
install(FILES ${PROJECT_SOURCE_DIR}/config/sysusers/hapticd.conf DESTINATION lib/sysusers.d)

install(FILES ${PROJECT_SOURCE_DIR}/man/hapticd.8 DESTINATION ${CMAKE_INSTALL_MANDIR}/man8)
install(FILES ${PROJECT_SOURCE_DIR}/man/haptic-tune.1 ${PROJECT_SOURCE_DIR}/man/hapticctl.1
        DESTINATION ${CMAKE_INSTALL_MANDIR}/man1)
install(FILES ${PROJECT_SOURCE_DIR}/man/hapticd.toml.5 DESTINATION ${CMAKE_INSTALL_MANDIR}/man5)

# The template unit and the default config (instance `sim`), for the install's own prefix.
install(CODE "
  set(HAPTICD_SOURCE_DIR \"${PROJECT_SOURCE_DIR}\")
  set(HAPTICD_STAGING_DIR \"${PROJECT_BINARY_DIR}/install-time\")
  set(HAPTICD_BINDIR \"${CMAKE_INSTALL_BINDIR}\")
  set(HAPTICD_DATA_INSTALL_DIR \"${HAPTICD_DATA_INSTALL_DIR}\")
  set(HAPTICD_UNIT_INSTALL_DIR \"${HAPTICD_UNIT_INSTALL_DIR}\")
  include(\"${PROJECT_SOURCE_DIR}/cmake/HapticdInstallTime.cmake\")
")

# The Python client (python/hapticd, docs/python.md), pure Python, where Debian's python3
# finds it for the prefix of the install: /usr/lib/python3/dist-packages for /usr (the .deb),
# else PREFIX/lib/python3.N/dist-packages (for /usr/local, on Debian's sys.path too).
execute_process(
  COMMAND /usr/bin/python3 -c "import sys; print('%d.%d' % sys.version_info[:2])"
  OUTPUT_VARIABLE HAPTICD_PYTHON_VERSION OUTPUT_STRIP_TRAILING_WHITESPACE
  COMMAND_ERROR_IS_FATAL ANY)
install(CODE "
  if(CMAKE_INSTALL_PREFIX STREQUAL \"/usr\")
    set(hapticd_python_dir \"\${CMAKE_INSTALL_PREFIX}/lib/python3/dist-packages\")
  else()
    set(hapticd_python_dir
        \"\${CMAKE_INSTALL_PREFIX}/lib/python${HAPTICD_PYTHON_VERSION}/dist-packages\")
  endif()
  file(INSTALL \"${PROJECT_SOURCE_DIR}/python/hapticd\" DESTINATION \"\${hapticd_python_dir}\"
       FILES_MATCHING PATTERN \"*.py\")
")

# The environment plugin ABI and hapticd's CMake package (docs/environment-plugins.md):
# <prefix>/include/hapticd/env/plugin_abi.h, and <prefix>/<libdir>/cmake/hapticd with the
# imported target hapticd::environment_plugin and hapticd_add_environment_plugin(); and the
# external world channel's layout, for a world in C or C++ (docs/external-worlds.md).
install(FILES ${PROJECT_SOURCE_DIR}/include/hapticd/env/plugin_abi.h
              ${PROJECT_SOURCE_DIR}/include/hapticd/env/external_world.h
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/hapticd/env)
install(TARGETS hapticd_environment_plugin EXPORT hapticdTargets)
set(HAPTICD_CMAKE_PACKAGE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/hapticd)
install(EXPORT hapticdTargets NAMESPACE hapticd:: DESTINATION ${HAPTICD_CMAKE_PACKAGE_DIR})
file(STRINGS ${PROJECT_SOURCE_DIR}/include/hapticd/env/plugin_abi.h abi_line
     REGEX "^#define HAPTICD_ENVIRONMENT_ABI_VERSION [0-9]+u$")
string(REGEX REPLACE ".* ([0-9]+)u$" "\\1" HAPTICD_ENVIRONMENT_ABI_VERSION "${abi_line}")
include(CMakePackageConfigHelpers)
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/hapticdConfig.cmake.in
  ${PROJECT_BINARY_DIR}/hapticdConfig.cmake
  INSTALL_DESTINATION ${HAPTICD_CMAKE_PACKAGE_DIR}
  PATH_VARS HAPTICD_PLUGIN_INSTALL_DIR)
write_basic_package_version_file(${PROJECT_BINARY_DIR}/hapticdConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/hapticdConfig.cmake
              ${PROJECT_BINARY_DIR}/hapticdConfigVersion.cmake
              ${PROJECT_SOURCE_DIR}/cmake/HapticdEnvironmentPlugin.cmake
        DESTINATION ${HAPTICD_CMAKE_PACKAGE_DIR})
