# `cmake --install`: the libraries, their public headers (Eigen and the standard library only)
# and inhandConfig.cmake exporting namespaced targets, so that a user's project says
#   find_package(inhand REQUIRED)
#   target_link_libraries(my_robot PRIVATE inhand::tracker inhand::sessions)
# The libraries are static: their third-party dependencies stay out of the headers, but the
# linker still needs them, so the config finds them (Debian's packages).
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(INHAND_INSTALLED_TARGETS inhand_core inhand_kinematics inhand_io inhand_contacts inhand_filter
  inhand_imageio inhand_renderer inhand_features inhand_sessions inhand_tracker inhand_strict)
foreach(target ${INHAND_INSTALLED_TARGETS})
  string(REPLACE "inhand_" "" export_name ${target})
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${export_name})
endforeach()
install(TARGETS ${INHAND_INSTALLED_TARGETS} EXPORT inhandTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})

# Public headers; internal ones (io/detail: nlohmann) and the simulator's stay in the tree.
foreach(dir estimator/core estimator/kinematics estimator/io estimator/contacts estimator/filter
            renderer features app/tracker)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${dir}/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
    FILES_MATCHING PATTERN "*.hpp" PATTERN "detail" EXCLUDE)
endforeach()
install(FILES ${PROJECT_SOURCE_DIR}/sessions/include/inhand/sessions/session.hpp
  ${PROJECT_SOURCE_DIR}/sessions/include/inhand/sessions/image_io.hpp DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/inhand/sessions)

install(EXPORT inhandTargets NAMESPACE inhand:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/inhand)
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/inhandConfig.cmake.in
  ${PROJECT_BINARY_DIR}/inhandConfig.cmake INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/inhand)
write_basic_package_version_file(${PROJECT_BINARY_DIR}/inhandConfigVersion.cmake COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/inhandConfig.cmake ${PROJECT_BINARY_DIR}/inhandConfigVersion.cmake
  DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/inhand)

# The tool: the inhand command, the project's hand and objects (the simulator finds them in
# PREFIX/share/inhand/assets from the executable or the Python module), the format's text.
install(TARGETS inhand RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
if(TARGET inhand_ros_node)
  # The live ROS 1 node, on PATH and where roslaunch looks for a package's nodes (lib/PACKAGE),
  # with the package's manifest and launch file in share/inhand.
  install(TARGETS inhand_ros_node RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  install(TARGETS inhand_ros_node RUNTIME DESTINATION ${CMAKE_INSTALL_LIBDIR}/inhand)
  install(FILES ${PROJECT_SOURCE_DIR}/app/ros_node/package.xml DESTINATION ${CMAKE_INSTALL_DATADIR}/inhand)
  install(FILES ${PROJECT_SOURCE_DIR}/app/ros_node/inhand.launch DESTINATION ${CMAKE_INSTALL_DATADIR}/inhand/launch)
endif()
install(DIRECTORY ${PROJECT_SOURCE_DIR}/assets/hands ${PROJECT_SOURCE_DIR}/assets/objects
  DESTINATION ${CMAKE_INSTALL_DATADIR}/inhand/assets)
install(FILES ${PROJECT_SOURCE_DIR}/README.md ${PROJECT_SOURCE_DIR}/sessions/FORMAT.md
  DESTINATION ${CMAKE_INSTALL_DOCDIR})

# `cpack -G DEB` in the build folder: one Debian package with all of the above under /usr. Its
# Depends come from dpkg-shlibdeps (the shared libraries the command and the module link), plus
# the interpreter and NumPy the module needs.
set(CPACK_PACKAGE_NAME inhand)
set(CPACK_PACKAGE_VENDOR "inhand")
set(CPACK_PACKAGE_CONTACT "inhand developers <inhand@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
  "in-hand object pose estimation (joints, torques, tags, image features) and its visual debugger")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
if(INHAND_BUILD_PYTHON)
  # The module is built for one interpreter version (its ABI): python3 of that version only.
  math(EXPR INHAND_NEXT_PYTHON_MINOR "${Python3_VERSION_MINOR} + 1")
  set(CPACK_DEBIAN_PACKAGE_DEPENDS "python3 (>= ${Python3_VERSION_MAJOR}.${Python3_VERSION_MINOR}), \
python3 (<< ${Python3_VERSION_MAJOR}.${INHAND_NEXT_PYTHON_MINOR}), python3-numpy")
  # evaluate draws its plots with matplotlib when it is there.
  set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "python3-matplotlib")
endif()
include(CPack)
