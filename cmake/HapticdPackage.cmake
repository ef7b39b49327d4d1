# The Debian package (`cpack -G DEB` in a build directory; scripts/ci-package builds, installs
# and checks it in CI; docs/install.md). The install is staged with DESTDIR and prefix /usr,
# so that the files written at install time (HapticdInstallTime.cmake) name /usr and /etc.
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME hapticd)
set(CPACK_PACKAGE_VENDOR "hapticd")
set(CPACK_PACKAGE_CONTACT "hapticd maintainers <hapticd@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
    "real-time haptic servo daemon with a passive virtual coupling")
# One string: set() with several would join them with ';', which the control file shows.
string(CONCAT CPACK_PACKAGE_DESCRIPTION
    "hapticd renders virtual environments on haptic devices (USB, HID, serial, simulated) "
    "through the virtual coupling of Adams & Hannaford, sized and checked by haptic-tune so "
    "that the interaction is stable for every passive operator. A systemd service per device.")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_INSTALL_PREFIX /usr)  # the prefix of the staged install (with CPACK_SET_DESTDIR)
set(CPACK_SET_DESTDIR ON)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
# Stripped executables and plugins (8 MB installed, not 236 MB); their debug information goes
# to hapticd-dbgsym, a .ddeb beside the package whose files gdb finds by build ID, as Debian's
# own packages ship it. CPack's CPACK_DEBIAN_DEBUGINFO_PACKAGE makes no .ddeb for a package
# without components (CMake 3.25), so HapticdSplitDebug.cmake does it, after the staged
# install and before the package is made.
set(HAPTICD_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PRE_BUILD_SCRIPTS ${PROJECT_SOURCE_DIR}/cmake/HapticdSplitDebug.cmake)
# Depends: from the executables' and plugins' shared libraries (dpkg-shlibdeps).
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
# The charts of haptic-tune plot and zwidth only.
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "python3-matplotlib")
# The default config is the administrator's to edit: dpkg keeps the edits on upgrade.
file(WRITE ${PROJECT_BINARY_DIR}/debian/conffiles "/etc/hapticd/sim.toml\n")
# The maintainer scripts (config/debian): the system user and group hapticd made on install,
# systemd and udev told of the new unit and rules, the instances stopped before a removal.
foreach(script postinst prerm postrm)
    file(COPY ${PROJECT_SOURCE_DIR}/config/debian/${script}
         DESTINATION ${PROJECT_BINARY_DIR}/debian
         FILE_PERMISSIONS OWNER_READ OWNER_WRITE OWNER_EXECUTE GROUP_READ GROUP_EXECUTE
                          WORLD_READ WORLD_EXECUTE)
    set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS
                                           ${PROJECT_SOURCE_DIR}/config/debian/${script})
endforeach()
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA
    ${PROJECT_BINARY_DIR}/debian/conffiles ${PROJECT_BINARY_DIR}/debian/postinst
    ${PROJECT_BINARY_DIR}/debian/prerm ${PROJECT_BINARY_DIR}/debian/postrm)
include(CPack)
