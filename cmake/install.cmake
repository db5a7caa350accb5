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
