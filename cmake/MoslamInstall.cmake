# `cmake --install build --prefix P`: the library for other programs (docs/RUNNING.md, "moslam
# inside other programs"). The modules of the SLAM core and the front door (moslam/moslam.h)
# with their headers under P/include/moslam/, the static libraries under P/lib, a CMake package
# (find_package(moslam): imported targets moslam::<module>, the dependencies found through
# find_dependency) and P/lib/pkgconfig/moslam.pc. net/ and weak/ (libtorch), runner/ and synth/
# (OSMesa) stay out: the front door needs neither, and a program that links moslam should not
# have to install libtorch.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

# In dependency order, users first (the order of the static libraries on a link line).
set(MOSLAM_INSTALLED_MODULES api slam mapio map vocab optim feature semantic eval io camera
                             geometry util)

foreach(module IN LISTS MOSLAM_INSTALLED_MODULES)
  set_target_properties(moslam_${module} PROPERTIES EXPORT_NAME ${module})
  install(TARGETS moslam_${module} EXPORT moslamTargets
          ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
          LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/src/moslam/${module}/
          DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/moslam/${module}
          FILES_MATCHING PATTERN "*.h" PATTERN "*.inc"
          PATTERN "*_test*" EXCLUDE PATTERN "test_*" EXCLUDE)
endforeach()
install(FILES ${PROJECT_SOURCE_DIR}/src/moslam/moslam.h
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/moslam)

set(MOSLAM_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/moslam)
install(EXPORT moslamTargets NAMESPACE moslam:: DESTINATION ${MOSLAM_CMAKE_DIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/moslamConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/moslamConfig.cmake
                              INSTALL_DESTINATION ${MOSLAM_CMAKE_DIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/moslamConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/moslamConfig.cmake
              ${PROJECT_BINARY_DIR}/moslamConfigVersion.cmake
        DESTINATION ${MOSLAM_CMAKE_DIR})

# pkg-config: the libraries in link order, then what they need. Ceres and cereal ship no .pc
# file in Debian 12: Ceres is named on Libs with glog (its headers call glog; its other
# dependencies come with libceres.so), cereal is header only and used in mapio's sources alone.
list(TRANSFORM MOSLAM_INSTALLED_MODULES PREPEND "-lmoslam_" OUTPUT_VARIABLE MOSLAM_PC_LIBS)
string(JOIN " " MOSLAM_PC_LIBS ${MOSLAM_PC_LIBS})
configure_file(${PROJECT_SOURCE_DIR}/cmake/moslam.pc.in ${PROJECT_BINARY_DIR}/moslam.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/moslam.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)

# ctest install/find_package: install into a temporary prefix, build examples/ against it and
# run it on a synthetic sequence (rendered by `moslam synth`), compile a program with pkg-config.
# Not in the sanitizer builds: the installed libraries would carry the sanitizer's flags.
if(MOSLAM_BUILD_TESTS AND MOSLAM_BUILD_APPS AND NOT MOSLAM_SANITIZE)
  add_test(NAME install/find_package
           COMMAND bash ${PROJECT_SOURCE_DIR}/examples/install_test.sh ${PROJECT_BINARY_DIR}
                   $<TARGET_FILE:moslam>)
  set_tests_properties(install/find_package PROPERTIES WORKING_DIRECTORY ${PROJECT_SOURCE_DIR}
                                                       LABELS install COST 60)
endif()
