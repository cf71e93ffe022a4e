# `cmake --install BUILD [--prefix P]`: mca as a Debian-style daemon package (docs/install.md). One place for
# every install rule. FHS paths from GNUInstallDirs:
#   sbin/mcad                              the daemon (the test build mcad-test is never installed)
#   libexec/mca/mca-dds-bridge             mcad's DDS publisher, a process of its own (docs/dds.md)
#   bin/mca-*                              tools: mca-sim, mca-monitor, mca-record, mca-geom, mca-armsim, ...
#   include/mca/*.h                        the public headers of the exported libraries
#   lib/libmca_*.a, lib/cmake/mca/         static libraries and the CMake package: find_package(mca) gives
#                                          mca::core (real time), mca::model (URDF, scenarios), mca::arm,
#                                          mca::sim_arm, mca::sim, mca::arm_can, mca::dds
#   etc/mca/cells, etc/mca/dds             what an operator edits (cells, Cyclone DDS configurations)
#   share/mca/{robots,scenarios,can,ros2}  models, tasks, the DBC, the RViz view; share/doc/mca the docs
#   share/mca/security                     make_security.sh and the DDS Security templates (docs/security.md)
#   lib/systemd/system/mcad@.service       the unit, with this prefix's paths
# With the prefix /usr (the Debian package, cmake/package.cmake) etc is /etc and the unit goes to
# /lib/systemd/system: absolute, so install with DESTDIR (cpack does) rather than --prefix.
# A cell's relative paths find share/mca through the search path (docs/daemon.md): the running program's
# own prefix's etc/mca and share/mca first (so any --prefix works), then this prefix's, built in.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(MCA_EXPORTED core body geom errbuf model arm sim_arm sim arm_can canopen dds)
foreach(lib ${MCA_EXPORTED})
  set(t mca_${lib})
  if(NOT TARGET ${t})
    continue()
  endif()
  # source-tree include folders for the build, include/ once installed
  get_target_property(inc ${t} INTERFACE_INCLUDE_DIRECTORIES)
  if(NOT inc)
    set(inc "")
  endif()
  set(fixed "")
  foreach(d ${inc})
    if(d MATCHES "^\\$<")
      list(APPEND fixed "${d}")
    else()
      list(APPEND fixed "$<BUILD_INTERFACE:${d}>")
      if(IS_DIRECTORY "${d}/mca" AND NOT d MATCHES "test_include")
        install(DIRECTORY "${d}/mca" DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} FILES_MATCHING PATTERN "*.h")
      endif()
    endif()
  endforeach()
  list(APPEND fixed "$<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>")
  set_target_properties(${t} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${fixed}" EXPORT_NAME ${lib})
  install(TARGETS ${t} EXPORT mcaTargets ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
endforeach()
install(EXPORT mcaTargets NAMESPACE mca:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/mca)
configure_package_config_file("${CMAKE_SOURCE_DIR}/cmake/mcaConfig.cmake.in" "${CMAKE_BINARY_DIR}/mcaConfig.cmake"
                              INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/mca)
write_basic_package_version_file("${CMAKE_BINARY_DIR}/mcaConfigVersion.cmake" COMPATIBILITY SameMinorVersion)
install(FILES "${CMAKE_BINARY_DIR}/mcaConfig.cmake" "${CMAKE_BINARY_DIR}/mcaConfigVersion.cmake"
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/mca)

install(TARGETS mcad RUNTIME DESTINATION ${CMAKE_INSTALL_SBINDIR})
# mcad's DDS publisher process: found by mcad in its own prefix's libexec/mca (then MCA_LIBEXECDIR,
# daemon/CMakeLists.txt)
install(TARGETS mca-dds-bridge RUNTIME DESTINATION ${CMAKE_INSTALL_LIBEXECDIR}/mca)
set(MCA_INSTALLED_TOOLS mca-sim mca-monitor mca-record mca-geom mca-armsim mca-drivesim mca-stopcheck
                        mca-simarm-trace mca-dds-synth)
foreach(tool ${MCA_INSTALLED_TOOLS})
  if(TARGET ${tool})
    install(TARGETS ${tool} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  endif()
endforeach()

# etc: relative to the prefix (so `cmake --install --prefix P` moves it) except where GNUInstallDirs puts it
# outside the prefix: /etc for the prefix /usr (the Debian package, cmake/package.cmake), /etc/opt for /opt
if(CMAKE_INSTALL_FULL_SYSCONFDIR STREQUAL "${CMAKE_INSTALL_PREFIX}/${CMAKE_INSTALL_SYSCONFDIR}")
  set(MCA_ETC_DEST ${CMAKE_INSTALL_SYSCONFDIR}/mca)
else()
  set(MCA_ETC_DEST ${CMAKE_INSTALL_FULL_SYSCONFDIR}/mca)
endif()
install(DIRECTORY "${CMAKE_SOURCE_DIR}/config/cells" "${CMAKE_SOURCE_DIR}/config/dds" DESTINATION ${MCA_ETC_DEST})
install(DIRECTORY "${CMAKE_SOURCE_DIR}/config/robots" DESTINATION ${CMAKE_INSTALL_DATADIR}/mca
        FILES_MATCHING PATTERN "*.urdf")
install(DIRECTORY "${CMAKE_SOURCE_DIR}/config/scenarios" "${CMAKE_SOURCE_DIR}/config/can"
                  "${CMAKE_SOURCE_DIR}/config/ros2" DESTINATION ${CMAKE_INSTALL_DATADIR}/mca)
if(IS_DIRECTORY "${CMAKE_SOURCE_DIR}/config/canopen")
  install(DIRECTORY "${CMAKE_SOURCE_DIR}/config/canopen" DESTINATION ${CMAKE_INSTALL_DATADIR}/mca)
endif()
install(PROGRAMS "${CMAKE_SOURCE_DIR}/config/systemd/mcad-run.sh" DESTINATION ${CMAKE_INSTALL_DATADIR}/mca)
# DDS Security (docs/security.md): the script and the unsigned templates; the signed files and keys it makes
# are the site's (MCA_SECURITY_DIR, default /etc/mca/security), never installed from here
install(PROGRAMS "${CMAKE_SOURCE_DIR}/config/security/make_security.sh" DESTINATION ${CMAKE_INSTALL_DATADIR}/mca/security)
install(FILES "${CMAKE_SOURCE_DIR}/config/security/governance_protected.xml"
              "${CMAKE_SOURCE_DIR}/config/security/governance_open.xml"
              "${CMAKE_SOURCE_DIR}/config/security/permissions.xml" DESTINATION ${CMAKE_INSTALL_DATADIR}/mca/security)
install(DIRECTORY "${CMAKE_SOURCE_DIR}/docs/" DESTINATION ${CMAKE_INSTALL_DOCDIR} PATTERN "bench-runs" EXCLUDE)
install(FILES "${CMAKE_SOURCE_DIR}/README.md" DESTINATION ${CMAKE_INSTALL_DOCDIR})

# the unit with this prefix's paths (the file in config/systemd/ names /usr/local)
file(READ "${CMAKE_SOURCE_DIR}/config/systemd/mcad@.service" unit)
string(REPLACE "/usr/local/sbin/mcad" "${CMAKE_INSTALL_FULL_SBINDIR}/mcad" unit "${unit}")
string(REPLACE "/etc/mca/" "${CMAKE_INSTALL_FULL_SYSCONFDIR}/mca/" unit "${unit}")
string(REPLACE "/usr/local/share/doc/mca" "${CMAKE_INSTALL_FULL_DOCDIR}" unit "${unit}")
file(WRITE "${CMAKE_BINARY_DIR}/mcad@.service" "${unit}")
# prefix/lib/systemd/system (systemd also reads /usr/local/lib/systemd/system), but for the prefix /usr
# Debian 12's unit folder /lib/systemd/system (`pkg-config --variable=systemdsystemunitdir systemd`): bookworm
# packages ship their units there, not in /usr/lib (the usrmerge moratorium)
if(CMAKE_INSTALL_PREFIX STREQUAL "/usr")
  set(MCA_UNIT_DEST /lib/systemd/system)
else()
  set(MCA_UNIT_DEST lib/systemd/system)
endif()
install(FILES "${CMAKE_BINARY_DIR}/mcad@.service" DESTINATION ${MCA_UNIT_DEST})

# every target the rules above install: `cmake --build B --target mca-installed` builds just what
# `cmake --install` and cpack need (tools/deb/build_deb.sh; no tests, benches or fuzzers)
add_custom_target(mca-installed)
foreach(t mcad mca-dds-bridge ${MCA_INSTALLED_TOOLS})
  if(TARGET ${t})
    add_dependencies(mca-installed ${t})
  endif()
endforeach()
foreach(lib ${MCA_EXPORTED})
  if(TARGET mca_${lib})
    add_dependencies(mca-installed mca_${lib})
  endif()
endforeach()
