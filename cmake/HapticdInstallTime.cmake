# Runs at install time (cmake/HapticdInstall.cmake's install(CODE)), when CMAKE_INSTALL_PREFIX
# is the install's: /usr for the .deb, /usr/local or --prefix for `cmake --install`.
# file(INSTALL) honours DESTDIR and records the files in install_manifest.txt.

# The files written here are staged per install (prefix and DESTDIR): two installs of one build
# at once (the InstalledTree tests under ctest -j) must not write each other's unit.
string(MD5 install_key "${CMAKE_INSTALL_PREFIX}|$ENV{DESTDIR}")
set(HAPTICD_STAGING_DIR "${HAPTICD_STAGING_DIR}/${install_key}")

# The system configuration directory as GNUInstallDirs has it: /etc for prefix /usr. The
# unit's ConfigurationDirectory= names a directory below /etc only, so another prefix's unit
# says where its configs are instead.
if(CMAKE_INSTALL_PREFIX STREQUAL "/usr")
  set(HAPTICD_CONFIG_INSTALL_DIR "/etc/hapticd")
  set(HAPTICD_CONFIGURATION_DIRECTORY "ConfigurationDirectory=hapticd")
else()
  set(HAPTICD_CONFIG_INSTALL_DIR "${CMAKE_INSTALL_PREFIX}/etc/hapticd")
  set(HAPTICD_CONFIGURATION_DIRECTORY
      "# (no ConfigurationDirectory=, which is below /etc: the configs are in ${HAPTICD_CONFIG_INSTALL_DIR})")
endif()
set(HAPTICD_INSTALLED_BINDIR "${CMAKE_INSTALL_PREFIX}/${HAPTICD_BINDIR}")

# hapticd@.service: instance NAME runs ${HAPTICD_CONFIG_INSTALL_DIR}/NAME.toml.
configure_file("${HAPTICD_SOURCE_DIR}/config/systemd/hapticd@.service.in"
               "${HAPTICD_STAGING_DIR}/hapticd@.service" @ONLY)
file(INSTALL "${HAPTICD_STAGING_DIR}/hapticd@.service"
     DESTINATION "${CMAKE_INSTALL_PREFIX}/${HAPTICD_UNIT_INSTALL_DIR}")

# sim.toml: config/hapticd.toml with its scene path made absolute, since the scenes are
# installed in the data directory, not next to it.
file(READ "${HAPTICD_SOURCE_DIR}/config/hapticd.toml" default_config)
set(relative_scene "file = \"scenes/demo-wall.toml\"")
string(FIND "${default_config}" "${relative_scene}" at)
if(at EQUAL -1)
  message(FATAL_ERROR "config/hapticd.toml no longer says ${relative_scene}: update "
                      "cmake/HapticdInstallTime.cmake, which makes that path absolute")
endif()
string(REPLACE "${relative_scene}"
       "file = \"${CMAKE_INSTALL_PREFIX}/${HAPTICD_DATA_INSTALL_DIR}/scenes/demo-wall.toml\""
       default_config "${default_config}")
string(PREPEND default_config
       "# Installed as ${HAPTICD_CONFIG_INSTALL_DIR}/sim.toml: `systemctl start hapticd@sim` "
       "runs it.\n")
file(WRITE "${HAPTICD_STAGING_DIR}/sim.toml" "${default_config}")
file(INSTALL "${HAPTICD_STAGING_DIR}/sim.toml" DESTINATION "${HAPTICD_CONFIG_INSTALL_DIR}")
