# SPDX-License-Identifier: Apache-2.0
# `cmake --install` layout and the Debian package (CPack DEB), issue 7 / docs/deployment.md:
#   <prefix>/bin                      camera_node, estimator_node and the tools
#   <prefix>/share/panoptes/dds       DDS profiles (bus.cpp finds loopback.xml here by default)
#   <prefix>/share/panoptes/scenes    simulator scenes
#   <prefix>/share/panoptes/markersets  marker sets on people (docs/marker_sets.md)
#   <prefix>/share/panoptes/examples  per-camera and estimator settings (4-camera lab, simulator)
#   <prefix>/share/doc/panoptes       the guides
#   /lib/systemd/system (deb) or <prefix>/lib/systemd/system: units whose paths point at the above
#   /etc/panoptes                     settings the units read (created, left to the administrator)
#   <prefix>/lib/libpanoptes_client.so*, <prefix>/include/panoptes/client: the client library, with
#   <prefix>/lib/cmake/Panoptes (find_package(Panoptes) -> Panoptes::client) and
#   <prefix>/lib/pkgconfig/panoptes-client.pc (docs/clients.md)
#   <prefix>/lib/python3/dist-packages/panoptes: the Python package (common/client/python)
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

install(TARGETS camera_node estimator_node panoptes_ctl panoptes_sim_tool panoptes_plan panoptes_export panoptes_record panoptes_replay panoptes_eval panoptes_demo panoptes_label
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})

# The client library and its CMake and pkg-config packages.
install(TARGETS panoptes_client EXPORT PanoptesTargets
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY ${PANOPTES_SOURCE_DIR}/common/client/include/panoptes/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/panoptes)
set(PANOPTES_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/Panoptes)
install(EXPORT PanoptesTargets NAMESPACE Panoptes:: DESTINATION ${PANOPTES_CMAKE_DIR})
configure_package_config_file(${PANOPTES_SOURCE_DIR}/cmake/PanoptesConfig.cmake.in
  ${CMAKE_BINARY_DIR}/PanoptesConfig.cmake INSTALL_DESTINATION ${PANOPTES_CMAKE_DIR})
# Before 1.0 a minor version may break the API: only the same minor version is compatible.
write_basic_package_version_file(${CMAKE_BINARY_DIR}/PanoptesConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_BINARY_DIR}/PanoptesConfig.cmake ${CMAKE_BINARY_DIR}/PanoptesConfigVersion.cmake
  DESTINATION ${PANOPTES_CMAKE_DIR})
configure_file(${PANOPTES_SOURCE_DIR}/cmake/panoptes-client.pc.in ${CMAKE_BINARY_DIR}/panoptes-client.pc @ONLY)
install(FILES ${CMAKE_BINARY_DIR}/panoptes-client.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)

set(PANOPTES_DATA_DIR ${CMAKE_INSTALL_DATADIR}/panoptes)
install(DIRECTORY ${PANOPTES_SOURCE_DIR}/deploy/dds/ DESTINATION ${PANOPTES_DATA_DIR}/dds FILES_MATCHING PATTERN "*.xml")
# DDS Security: the studio CA, identities and signed documents (docs/security.md).
install(PROGRAMS ${PANOPTES_SOURCE_DIR}/deploy/security/panoptes-security DESTINATION ${CMAKE_INSTALL_BINDIR})
install(DIRECTORY ${PANOPTES_SOURCE_DIR}/deploy/scenes/ DESTINATION ${PANOPTES_DATA_DIR}/scenes
  FILES_MATCHING PATTERN "*.yaml" PATTERN "*.trc")
install(DIRECTORY ${PANOPTES_SOURCE_DIR}/deploy/examples/ DESTINATION ${PANOPTES_DATA_DIR}/examples)
install(DIRECTORY ${PANOPTES_SOURCE_DIR}/deploy/markersets/ DESTINATION ${PANOPTES_DATA_DIR}/markersets
  FILES_MATCHING PATTERN "*.yaml")
install(FILES ${PANOPTES_SOURCE_DIR}/README.md ${PANOPTES_SOURCE_DIR}/LICENSE DESTINATION ${CMAKE_INSTALL_DOCDIR})
install(DIRECTORY ${PANOPTES_SOURCE_DIR}/docs/ DESTINATION ${CMAKE_INSTALL_DOCDIR} FILES_MATCHING PATTERN "*.md")

# The units name the installed files, so they are written at install time, when the prefix is
# known (cmake --install --prefix, or /usr inside the Debian package). Settings: /etc/panoptes.
install(CODE "
  set(prefix \"\${CMAKE_INSTALL_PREFIX}\")
  set(PANOPTES_BIN_DIR \"\${prefix}/${CMAKE_INSTALL_BINDIR}\")
  set(PANOPTES_DATA_DIR \"\${prefix}/${PANOPTES_DATA_DIR}\")
  set(PANOPTES_EXAMPLES_DIR \"\${PANOPTES_DATA_DIR}/examples\")
  set(PANOPTES_DOC_DIR \"\${prefix}/${CMAKE_INSTALL_DOCDIR}\")
  set(PANOPTES_CONFIG_DIR /etc/panoptes)
  # Debian keeps units in /lib/systemd/system whatever the prefix; elsewhere they follow it.
  if(prefix STREQUAL \"/usr\")
    set(unit_dir /lib/systemd/system)
  else()
    set(unit_dir \"\${prefix}/lib/systemd/system\")
  endif()
  foreach(unit camera_node@.service estimator_node.service panoptes-discovery.service)
    message(STATUS \"Installing: \$ENV{DESTDIR}\${unit_dir}/\${unit}\")
    configure_file(\"${PANOPTES_SOURCE_DIR}/deploy/systemd/\${unit}.in\" \"\$ENV{DESTDIR}\${unit_dir}/\${unit}\" @ONLY)
  endforeach()
")

# Debian package: cmake --build build && (cd build && cpack -G DEB) -> build/panoptes_<version>_amd64.deb,
# installed under /usr whatever CMAKE_INSTALL_PREFIX is. Library dependencies from dpkg-shlibdeps.
set(CPACK_PACKAGE_NAME panoptes)
set(CPACK_PACKAGE_VENDOR "Panoptes")
set(CPACK_PACKAGE_CONTACT "Panoptes developers <panoptes@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "Distributed optical motion tracking over DDS (camera and estimator nodes)")
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
# libpanoptes_client.so: a shlibs file and the ldconfig trigger.
set(CPACK_DEBIAN_PACKAGE_GENERATE_SHLIBS ON)
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "fastdds-tools, aravis-tools, python3-numpy")  # python3-numpy: the panoptes Python package
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
# Staged with DESTDIR and the prefix /usr, so the units written at install time name /usr/bin/...
set(CPACK_SET_DESTDIR ON)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_INSTALL_PREFIX /usr)
set(CPACK_GENERATOR DEB)
include(CPack)
