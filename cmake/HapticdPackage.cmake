# The Debian package (`cpack -G DEB` in a build directory; scripts/ci-package builds, installs
# and checks it in CI; docs/install.md). The install is staged with DESTDIR and prefix /usr,
# so that the files written at install time (HapticdInstallTime.cmake) name /usr and /etc.
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME hapticd)
set(CPACK_PACKAGE_VENDOR "hapticd")
set(CPACK_PACKAGE_CONTACT "hapticd maintainers <hapticd@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
    "real-time haptic servo daemon with a passive virtual coupling")
set(CPACK_PACKAGE_DESCRIPTION
    "hapticd renders virtual environments on haptic devices (USB, HID, serial, simulated) "
    "through the virtual coupling of Adams & Hannaford, sized and checked by haptic-tune so "
    "that the interaction is stable for every passive operator. A systemd service per device.")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_INSTALL_PREFIX /usr)  # the prefix of the staged install (with CPACK_SET_DESTDIR)
set(CPACK_SET_DESTDIR ON)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
# Depends: from the executables' and plugins' shared libraries (dpkg-shlibdeps).
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
# The charts of haptic-tune plot and zwidth only.
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "python3-matplotlib")
# The default config is the administrator's to edit: dpkg keeps the edits on upgrade.
file(WRITE ${PROJECT_BINARY_DIR}/debian/conffiles "/etc/hapticd/sim.toml\n")
# The group of the control sockets (config/sysusers/hapticd.conf), made on install as
# debhelper's dh_installsysusers would.
file(WRITE ${PROJECT_BINARY_DIR}/debian/postinst [=[#!/bin/sh
set -e
if [ "$1" = configure ] && command -v systemd-sysusers >/dev/null; then
    systemd-sysusers hapticd.conf
fi
]=])
file(CHMOD ${PROJECT_BINARY_DIR}/debian/postinst
     PERMISSIONS OWNER_READ OWNER_WRITE OWNER_EXECUTE GROUP_READ GROUP_EXECUTE WORLD_READ
                 WORLD_EXECUTE)
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA ${PROJECT_BINARY_DIR}/debian/conffiles
                                       ${PROJECT_BINARY_DIR}/debian/postinst)
include(CPack)
