# Install rules of the library (included from src/CMakeLists.txt, after the targets exist):
# libraries, header, the public Fortran modules, the CMake package (vci::), pkg-config, and the
# examples and docs under GNUInstallDirs' places (docs/BUILD.md, "What is installed").
include(CMakePackageConfigHelpers)
set(VCI_INSTALL_CMAKEDIR "${CMAKE_INSTALL_LIBDIR}/cmake/vci")
install(TARGETS ${VCI_LIBRARY_TARGETS} EXPORT vci-targets
  ARCHIVE DESTINATION "${CMAKE_INSTALL_LIBDIR}"
  LIBRARY DESTINATION "${CMAKE_INSTALL_LIBDIR}"
  RUNTIME DESTINATION "${CMAKE_INSTALL_BINDIR}")
install(FILES "${PROJECT_SOURCE_DIR}/include/vci.h" DESTINATION "${CMAKE_INSTALL_INCLUDEDIR}")

# Only the modules a user `use`s: the umbrella `vci` and the optional layers beside it. gfortran
# writes into each .mod everything its public entities need (the types of vci_model, vci_integrator
# ... travel inside vci.mod), so a program compiles against these alone; the export test builds
# the examples from an install that has nothing else. Submodule files (.smod) are never needed by
# users. Any other module of src/ is internal (docs/VERSIONING.md).
set(VCI_PUBLIC_MODULES vci vci_ensemble)
if(VCI_WITH_HDF5)
  list(APPEND VCI_PUBLIC_MODULES vci_hdf5_output vci_ensemble_h5 vci_ensemble_mpi)
endif()
set(_vci_mod_files "")
foreach(_m IN LISTS VCI_PUBLIC_MODULES)
  list(APPEND _vci_mod_files "${VCI_MODULE_DIR}/${_m}.mod")
endforeach()
install(FILES ${_vci_mod_files} DESTINATION "${VCI_INSTALL_MODULEDIR}")

install(EXPORT vci-targets NAMESPACE vci:: DESTINATION "${VCI_INSTALL_CMAKEDIR}")
set(VCI_CONFIG_HDF5_LIBRARIES "${HDF5_Fortran_LIBRARIES}")   # for consumers without Fortran
set(VCI_CONFIG_OPENMP_LIBRARIES "${OpenMP_Fortran_LIBRARIES}")
set(VCI_CONFIG_MPI_LIBRARIES "${MPI_Fortran_LIBRARIES}")
configure_package_config_file("${PROJECT_SOURCE_DIR}/cmake/vci-config.cmake.in"
  "${PROJECT_BINARY_DIR}/vci-config.cmake" INSTALL_DESTINATION "${VCI_INSTALL_CMAKEDIR}")
# docs/VERSIONING.md: before 1.0 a minor release may change the Fortran API, from 1.0 only a major one
if(PROJECT_VERSION_MAJOR EQUAL 0)
  set(_vci_compat SameMinorVersion)
else()
  set(_vci_compat SameMajorVersion)
endif()
write_basic_package_version_file("${PROJECT_BINARY_DIR}/vci-config-version.cmake"
  VERSION ${PROJECT_VERSION} COMPATIBILITY ${_vci_compat})
install(FILES "${PROJECT_BINARY_DIR}/vci-config.cmake" "${PROJECT_BINARY_DIR}/vci-config-version.cmake"
  DESTINATION "${VCI_INSTALL_CMAKEDIR}")

# --- pkg-config ---
# Relocatable (the prefix is found from the .pc file's own place). A shared link needs only
# `Libs`; a static one (`pkg-config --static`) adds the dependencies, named as the system's own
# .pc files name them (Requires.private: Debian ships lapack.pc, hdf5-serial.pc / hdf5-openmpi.pc,
# ompi-fort.pc), and, in Libs.private, what no .pc file covers: HDF5's Fortran library, the
# OpenMP and Fortran runtimes, -pthread. Never absolute paths of shared libraries.
find_program(VCI_PKG_CONFIG_EXECUTABLE pkg-config)
mark_as_advanced(VCI_PKG_CONFIG_EXECUTABLE)

# vci_pc_module(<out> <library> <candidates...>): the first pkg-config module among the candidates
# whose library directory holds <library> (the file vci linked, or a link to the same file: Debian
# has libmpi*.so both in the multiarch directory and in openmpi/lib), else "".
function(vci_pc_module out lib)
  set(${out} "" PARENT_SCOPE)
  if(NOT VCI_PKG_CONFIG_EXECUTABLE)
    return()
  endif()
  get_filename_component(_name "${lib}" NAME)
  get_filename_component(_real "${lib}" REALPATH)
  foreach(_cand IN LISTS ARGN)
    execute_process(COMMAND "${VCI_PKG_CONFIG_EXECUTABLE}" --variable=libdir "${_cand}"
      OUTPUT_VARIABLE _libdir RESULT_VARIABLE _rc1 OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
    execute_process(COMMAND "${VCI_PKG_CONFIG_EXECUTABLE}" --libs-only-L "${_cand}"
      OUTPUT_VARIABLE _ldirs RESULT_VARIABLE _rc2 OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
    if(NOT _rc1 EQUAL 0 OR NOT _rc2 EQUAL 0)
      continue()
    endif()
    string(REPLACE "-L" ";" _ldirs "${_ldirs}")
    foreach(_d IN LISTS _libdir _ldirs)
      string(STRIP "${_d}" _d)
      if(_d)
        get_filename_component(_cand_lib "${_d}/${_name}" REALPATH)
        if(EXISTS "${_d}/${_name}" AND _cand_lib STREQUAL _real)
          set(${out} "${_cand}" PARENT_SCOPE)
          return()
        endif()
      endif()
    endforeach()
  endforeach()
endfunction()

# vci_pc_flags(<out> <libs...>): -L/-l flags for libraries given as paths, names or flags (no -L
# for the compiler's own directories); glibc's libpthread.a / libdl.a stubs are left to -pthread.
function(vci_pc_flags out)
  set(_flags "")
  foreach(_lib IN LISTS ARGN)
    if(_lib MATCHES "^-")
      string(APPEND _flags " ${_lib}")
    elseif(IS_ABSOLUTE "${_lib}")
      get_filename_component(_name "${_lib}" NAME)
      if(_name MATCHES "^lib(pthread|dl|rt)\\.")
        continue()
      endif()
      string(REGEX REPLACE "^lib(.*)\\.(so|a|dylib)(\\..*)?$" "\\1" _name "${_name}")
      get_filename_component(_dir "${_lib}" DIRECTORY)
      if(NOT _dir IN_LIST CMAKE_C_IMPLICIT_LINK_DIRECTORIES AND
         NOT _dir IN_LIST CMAKE_Fortran_IMPLICIT_LINK_DIRECTORIES)
        string(APPEND _flags " -L${_dir}")
      endif()
      string(APPEND _flags " -l${_name}")
    elseif(_lib MATCHES "^(pthread|dl|rt)$")
      continue()
    else()
      string(APPEND _flags " -l${_lib}")
    endif()
  endforeach()
  set(${out} "${_flags}" PARENT_SCOPE)
endfunction()

file(RELATIVE_PATH VCI_PC_PREFIX_FROM_PCDIR "/_p/${CMAKE_INSTALL_LIBDIR}/pkgconfig" "/_p")
set(_vci_requires "")
set(_vci_private_libs "")
# LAPACK (and the BLAS under it)
list(GET LAPACK_LIBRARIES 0 _first)
set(_mod "")
if(IS_ABSOLUTE "${_first}")
  vci_pc_module(_mod "${_first}" lapack)
endif()
if(_mod)
  list(APPEND _vci_requires ${_mod})
else()
  list(APPEND _vci_private_libs ${LAPACK_LIBRARIES})
endif()
# SuiteSparse KLU (VCI_SPARSE): Debian ships no .pc file for it; by name (a static link of libvci
# needs it, a shared one finds it through libvci's own DT_NEEDED)
if(VCI_SPARSE)
  list(APPEND _vci_private_libs ${VCI_KLU_LIBRARY})
endif()
# HDF5: the C library through its .pc file, the Fortran library beside it by name
if(VCI_WITH_HDF5)
  set(_hdf5_c "")
  set(_hdf5_fortran "")
  foreach(_lib IN LISTS HDF5_Fortran_LIBRARIES)
    if(_lib MATCHES "/libhdf5_fortran\\.")
      set(_hdf5_fortran "${_lib}")
    elseif(_lib MATCHES "/libhdf5\\.")
      set(_hdf5_c "${_lib}")
    endif()
  endforeach()
  set(_mod "")
  if(_hdf5_c)
    if(HDF5_IS_PARALLEL)
      vci_pc_module(_mod "${_hdf5_c}" hdf5-openmpi hdf5-mpich hdf5-mpi hdf5)
    else()
      vci_pc_module(_mod "${_hdf5_c}" hdf5-serial hdf5)
    endif()
  endif()
  if(_mod AND _hdf5_fortran)
    list(APPEND _vci_requires ${_mod})
    list(APPEND _vci_private_libs "${_hdf5_fortran}")
  else()
    list(APPEND _vci_private_libs ${HDF5_Fortran_LIBRARIES})
  endif()
endif()
set(VCI_PC_WITH_OPENMP 0)
set(VCI_PC_WITH_MPI 0)
set(VCI_PC_CFLAGS_EXTRA "")
if(VCI_WITH_OPENMP)
  set(VCI_PC_WITH_OPENMP 1)
  list(APPEND _vci_private_libs ${OpenMP_Fortran_LIBRARIES})
endif()
if(VCI_WITH_MPI)
  # the MPI library vci was built with; `use vci_ensemble_mpi` also needs MPI's module directory
  set(VCI_PC_WITH_MPI 1)
  list(GET MPI_Fortran_LIBRARIES 0 _first)
  vci_pc_module(_mod "${_first}" ompi-fort mpich-fort mpi-fort)
  if(_mod)
    list(APPEND _vci_requires ${_mod})
  else()
    list(APPEND _vci_private_libs ${MPI_Fortran_LIBRARIES})
  endif()
  set(_dirs ${MPI_Fortran_MODULE_DIR} ${MPI_Fortran_INCLUDE_DIRS})
  list(REMOVE_DUPLICATES _dirs)
  foreach(_dir IN LISTS _dirs)
    string(APPEND VCI_PC_CFLAGS_EXTRA " -I${_dir}")
  endforeach()
endif()
foreach(_lib IN LISTS CMAKE_Fortran_IMPLICIT_LINK_LIBRARIES)
  if(_lib MATCHES "^(gfortran|quadmath|m)$")
    list(APPEND _vci_private_libs ${_lib})
  endif()
endforeach()
list(REMOVE_DUPLICATES _vci_private_libs)
vci_pc_flags(VCI_PC_LIBS_PRIVATE ${_vci_private_libs})
string(APPEND VCI_PC_LIBS_PRIVATE " -pthread")   # the C ABI's locks
string(STRIP "${VCI_PC_LIBS_PRIVATE}" VCI_PC_LIBS_PRIVATE)
list(REMOVE_DUPLICATES _vci_requires)
string(REPLACE ";" ", " VCI_PC_REQUIRES_PRIVATE "${_vci_requires}")
configure_file("${PROJECT_SOURCE_DIR}/cmake/vci.pc.in" "${PROJECT_BINARY_DIR}/vci.pc" @ONLY)
install(FILES "${PROJECT_BINARY_DIR}/vci.pc" DESTINATION "${CMAKE_INSTALL_LIBDIR}/pkgconfig")

# --- examples and docs: <prefix>/share/doc/vci (CMAKE_INSTALL_DOCDIR) ---
# The examples' CMakeLists.txt also builds on its own against an installed vci (examples/README.md).
install(DIRECTORY "${PROJECT_SOURCE_DIR}/examples/" DESTINATION "${CMAKE_INSTALL_DOCDIR}/examples")
install(FILES "${PROJECT_SOURCE_DIR}/README.md" "${PROJECT_SOURCE_DIR}/LICENSE"
  "${PROJECT_SOURCE_DIR}/CHANGELOG.md" "${PROJECT_SOURCE_DIR}/CITATION.cff"
  DESTINATION "${CMAKE_INSTALL_DOCDIR}")
install(DIRECTORY "${PROJECT_SOURCE_DIR}/docs/" DESTINATION "${CMAKE_INSTALL_DOCDIR}/docs")
# the API reference, when `cmake --build <dir> --target vci_docs` has made it (docs/BUILD.md)
install(DIRECTORY "${PROJECT_BINARY_DIR}/apidocs/html/" DESTINATION "${CMAKE_INSTALL_DOCDIR}/api" OPTIONAL)
