# ---- the Debian package: `cpack -G DEB` in a build directory gives qm3d_VERSION_amd64.deb ----
# It holds what `cmake --install` installs (the tool, the static libraries with their headers,
# the CMake package, the LAB2000HL tables when they were found, the demo data) under /usr, and
# the Python package in /usr/lib/python3/dist-packages. The tool and the Python module find
# their tables in /usr/share/qm3d/lab2000hl by themselves (beside /usr/bin/qm3d and
# /usr/lib/python3/dist-packages/qm3d). Included by the top-level CMakeLists.txt after python/.

set(QM3D_PACKAGE_MAINTAINER "qm3d maintainers <maintainers@users.noreply.h-seed-84690eed.example>"
    CACHE STRING "Maintainer field of the Debian package (Name <e-mail>)")
set(QM3D_PACKAGE_HOMEPAGE "" CACHE STRING
    "Homepage field of the Debian package (left out when empty)")

# Debian installs python3 modules for every supported interpreter in /usr/lib/python3/
# dist-packages (the ABI-tagged name of the compiled module keeps versions apart), not in
# /usr/lib/python3.X, where `cmake --install` puts them for /usr/local (QM3D_PYTHON_INSTALL_DIR,
# python/CMakeLists.txt). So the package has its own copy of the Python install rules, in a
# component that only CPack installs (EXCLUDE_FROM_ALL: `cmake --install` never does).
set(_qm3d_deb_components Unspecified)
set(_qm3d_deb_python_depends "")
if(TARGET qm3d_python)
  set(_qm3d_deb_pydir lib/python3/dist-packages/qm3d)
  install(TARGETS qm3d_python LIBRARY DESTINATION ${_qm3d_deb_pydir}
          COMPONENT deb_python EXCLUDE_FROM_ALL)
  file(GLOB _qm3d_deb_py CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/python/qm3d/*.py)
  install(FILES ${_qm3d_deb_py} DESTINATION ${_qm3d_deb_pydir}
          COMPONENT deb_python EXCLUDE_FROM_ALL)
  list(APPEND _qm3d_deb_components deb_python)
  # The module does not link libpython (dpkg-shlibdeps cannot see the interpreter): it needs the
  # interpreter version it was built for, and numpy, which python/qm3d/__init__.py imports.
  math(EXPR _qm3d_py_next "${PYTHON_VERSION_MINOR} + 1")
  set(_qm3d_deb_python_depends
      "python3 (>= ${PYTHON_VERSION_MAJOR}.${PYTHON_VERSION_MINOR}), python3 (<< ${PYTHON_VERSION_MAJOR}.${_qm3d_py_next}), python3-numpy")
endif()
# One entry per component: build directory, project, component, subdirectory (CPack installs the
# components listed here into one package).
set(CPACK_INSTALL_CMAKE_PROJECTS "")
foreach(_c ${_qm3d_deb_components})
  list(APPEND CPACK_INSTALL_CMAKE_PROJECTS "${PROJECT_BINARY_DIR};qm3d;${_c};/")
endforeach()

set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME qm3d)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_VENDOR "The qm3d developers")
set(CPACK_PACKAGE_CONTACT "${QM3D_PACKAGE_MAINTAINER}")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "${PROJECT_DESCRIPTION}")
set(CPACK_PACKAGE_DESCRIPTION
    "qm3d scores the visual quality of coloured 3D content against a reference: CMDM and MSDM2
for meshes, PCQM for point clouds, MPEG pc_error's PSNR and the D_LAB colour baseline, with
the numbers of the reference tools. The package holds the qm3d tool, the Python package (for
Debian's python3), the static libraries with their headers and CMake package
(find_package(qm3d)), the LAB2000HL tables (MEPP-team/PCQM, MPL-2.0) and the demo data.")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)  # qm3d_VERSION_ARCH.deb
set(CPACK_DEBIAN_PACKAGE_MAINTAINER "${QM3D_PACKAGE_MAINTAINER}")
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
if(QM3D_PACKAGE_HOMEPAGE)
  set(CPACK_DEBIAN_PACKAGE_HOMEPAGE "${QM3D_PACKAGE_HOMEPAGE}")
endif()
# The shared libraries the tool and the module link (liblzf, stb, OpenMP, the C++ runtime) are
# found by dpkg-shlibdeps (Debian: dpkg-dev) from the binaries themselves, never listed here.
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_DEPENDS "${_qm3d_deb_python_depends}")
# Run-time files read when present: three.js inlined into HTML reports (QM3D_THREE_JS); the
# qm3d.dask module's pandas and distributed; the -dev packages a program using
# find_package(qm3d) needs (cmake/qm3dConfig.cmake.in: Eigen, CGAL, liblzf, nlohmann-json).
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "libjs-three")
set(CPACK_DEBIAN_PACKAGE_SUGGESTS
    "python3-pandas, python3-distributed, libeigen3-dev, libcgal-dev, liblzf-dev, nlohmann-json3-dev")
include(CPack)
