# Install rules of the library (included from src/CMakeLists.txt, after the targets exist):
# libraries, header, Fortran modules, the CMake package (vci::) and pkg-config.
# --- install: libraries, header, Fortran modules, CMake package (vci::), pkg-config ---
include(CMakePackageConfigHelpers)
set(VCI_INSTALL_CMAKEDIR "${CMAKE_INSTALL_LIBDIR}/cmake/vci")
install(TARGETS ${VCI_LIBRARY_TARGETS} EXPORT vci-targets
  ARCHIVE DESTINATION "${CMAKE_INSTALL_LIBDIR}"
  LIBRARY DESTINATION "${CMAKE_INSTALL_LIBDIR}"
  RUNTIME DESTINATION "${CMAKE_INSTALL_BINDIR}")
install(FILES "${PROJECT_SOURCE_DIR}/include/vci.h" DESTINATION "${CMAKE_INSTALL_INCLUDEDIR}")
install(DIRECTORY "${VCI_MODULE_DIR}/" DESTINATION "${VCI_INSTALL_MODULEDIR}"
  FILES_MATCHING PATTERN "*.mod" PATTERN "*.smod")
install(EXPORT vci-targets NAMESPACE vci:: DESTINATION "${VCI_INSTALL_CMAKEDIR}")
set(VCI_CONFIG_HDF5_LIBRARIES "${HDF5_Fortran_LIBRARIES}")   # for consumers without Fortran
set(VCI_CONFIG_OPENMP_LIBRARIES "${OpenMP_Fortran_LIBRARIES}")
set(VCI_CONFIG_MPI_LIBRARIES "${MPI_Fortran_LIBRARIES}")
configure_package_config_file("${PROJECT_SOURCE_DIR}/cmake/vci-config.cmake.in"
  "${PROJECT_BINARY_DIR}/vci-config.cmake" INSTALL_DESTINATION "${VCI_INSTALL_CMAKEDIR}")
# 0.x: a minor release may change the API
write_basic_package_version_file("${PROJECT_BINARY_DIR}/vci-config-version.cmake"
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES "${PROJECT_BINARY_DIR}/vci-config.cmake" "${PROJECT_BINARY_DIR}/vci-config-version.cmake"
  DESTINATION "${VCI_INSTALL_CMAKEDIR}")

# pkg-config: relocatable (prefix found from the .pc file's own place); Libs.private for static linking
file(RELATIVE_PATH VCI_PC_PREFIX_FROM_PCDIR "/_p/${CMAKE_INSTALL_LIBDIR}/pkgconfig" "/_p")
set(VCI_PC_LIBS_PRIVATE "")
set(_vci_pc_libs ${LAPACK_LIBRARIES})
if(VCI_WITH_HDF5)
  list(APPEND _vci_pc_libs ${HDF5_Fortran_LIBRARIES})
endif()
set(VCI_PC_WITH_OPENMP 0)
set(VCI_PC_WITH_MPI 0)
set(VCI_PC_CFLAGS_EXTRA "")
if(VCI_WITH_OPENMP)
  set(VCI_PC_WITH_OPENMP 1)
  list(APPEND _vci_pc_libs ${OpenMP_Fortran_LIBRARIES})
endif()
if(VCI_WITH_MPI)
  # the MPI library vci was built with; `use vci_ensemble_mpi` also needs MPI's module directory
  set(VCI_PC_WITH_MPI 1)
  list(APPEND _vci_pc_libs ${MPI_Fortran_LIBRARIES})
  set(_dirs ${MPI_Fortran_MODULE_DIR} ${MPI_Fortran_INCLUDE_DIRS})
  list(REMOVE_DUPLICATES _dirs)
  foreach(_dir IN LISTS _dirs)
    string(APPEND VCI_PC_CFLAGS_EXTRA " -I${_dir}")
  endforeach()
endif()
foreach(_lib IN LISTS _vci_pc_libs)
  if(_lib MATCHES "^-")
    string(APPEND VCI_PC_LIBS_PRIVATE " ${_lib}")
  elseif(IS_ABSOLUTE "${_lib}")
    string(APPEND VCI_PC_LIBS_PRIVATE " ${_lib}")
  else()
    string(APPEND VCI_PC_LIBS_PRIVATE " -l${_lib}")
  endif()
endforeach()
foreach(_lib IN LISTS CMAKE_Fortran_IMPLICIT_LINK_LIBRARIES)
  if(_lib MATCHES "^(gfortran|quadmath|m)$")
    string(APPEND VCI_PC_LIBS_PRIVATE " -l${_lib}")
  endif()
endforeach()
string(APPEND VCI_PC_LIBS_PRIVATE " -pthread")   # the C ABI's locks
string(STRIP "${VCI_PC_LIBS_PRIVATE}" VCI_PC_LIBS_PRIVATE)
configure_file("${PROJECT_SOURCE_DIR}/cmake/vci.pc.in" "${PROJECT_BINARY_DIR}/vci.pc" @ONLY)
install(FILES "${PROJECT_BINARY_DIR}/vci.pc" DESTINATION "${CMAKE_INSTALL_LIBDIR}/pkgconfig")
