# `cpack -G DEB` in a build configured with -DCMAKE_INSTALL_PREFIX=/usr: the Debian package mca
# (tools/deb/build_deb.sh, `make deb`, docs/install.md). CPack DEB rather than dpkg-buildpackage: the package
# is exactly the install rules of cmake/install.cmake (one place for them), it builds inside `make test`
# without a debian/ directory that would repeat the layout, debhelper or root, and dpkg-shlibdeps still
# computes Depends as Debian's own tools do.
#
# The package must come from its own configure with the prefix /usr, not from cpack of a /usr/local build with
# CPACK_PACKAGING_INSTALL_PREFIX=/usr: the unit is written with the configured prefix, and etc is /etc only
# for the prefix /usr (mcad finds its files and mca-dds-bridge relative to itself, docs/install.md).
# So `cpack`/`make package` exist only in a build with that prefix.
if(NOT CMAKE_INSTALL_PREFIX STREQUAL "/usr")
  return()
endif()

set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME mca)
set(CPACK_PACKAGE_VENDOR "mca")
set(CPACK_PACKAGE_CONTACT "mca maintainers <mca@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "dual-arm mutual-collision avoidance controller daemon")
set(CPACK_PACKAGE_DESCRIPTION
    "mcad drives two (or more) robot arms at 1 kHz with mutual-collision avoidance (PDNN-solved QP), on
simulated firmware, CAN FD (SocketCAN) or CANopen drives, publishing its state on DDS / ROS 2.
The package holds mcad and its DDS publisher, the mca-* tools, the cells in /etc/mca,
the robot models and tasks in /usr/share/mca, the unit mcad@.service (systemctl start mcad@CELL),
and the headers, static libraries and CMake package (find_package(mca)).")
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT) # mca_0.1.0_amd64.deb
set(CPACK_DEBIAN_PACKAGE_SECTION misc)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
set(CPACK_DEBIAN_PACKAGE_HOMEPAGE "https://localhost/mca")
# Depends from the ELF files by dpkg-shlibdeps (every library mcad links comes from a Debian 12 package:
# libcyaml1, liburdfdom-model3.0, libddsc0debian, libsystemd0, ...): a hand list would drift from what the
# binaries link.
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
# what an operator edits in /etc/mca is kept over upgrades and removal (dpkg conffiles)
file(GLOB_RECURSE mca_etc CONFIGURE_DEPENDS RELATIVE "${CMAKE_SOURCE_DIR}/config" "${CMAKE_SOURCE_DIR}/config/cells/*"
     "${CMAKE_SOURCE_DIR}/config/dds/*")
list(SORT mca_etc)
list(TRANSFORM mca_etc PREPEND "${CMAKE_INSTALL_FULL_SYSCONFDIR}/mca/")
list(JOIN mca_etc "\n" mca_etc)
file(WRITE "${CMAKE_BINARY_DIR}/deb/conffiles" "${mca_etc}\n")
# postinst/postrm: systemctl daemon-reload only (no unit is enabled or started by installing)
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA "${CMAKE_BINARY_DIR}/deb/conffiles" "${CMAKE_SOURCE_DIR}/tools/deb/postinst"
                                       "${CMAKE_SOURCE_DIR}/tools/deb/postrm")
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
set(CPACK_STRIP_FILES ON)
set(CPACK_OUTPUT_FILE_PREFIX "${CMAKE_BINARY_DIR}/deb")
include(CPack)
