# VciTesting.cmake -- register pFUnit (.pf) test suites with CTest.
#
#   vci_add_pf_suite(NAME <name> SOURCES <a.pf ...> [LINK <targets...>]
#                    [LABELS <labels...>] [WILL_FAIL]
#                    [EXTRA_SOURCES <plain .f90 support files...>])
#
# Uses pFUnit 4 (add_pfunit_ctest) when VCI_USE_PFUNIT is ON and
# find_package(PFUNIT) succeeds; otherwise falls back to pfunit_lite
# (cmake/pfunit_lite: pf2f90.py converter + `funit` runtime module).
# Either way it creates an executable target and a CTest test both called
# <name>.  After include(), VCI_PFUNIT_LITE is TRUE when the fallback is used.
# See docs/TESTING.md.
#
# Deliberately no include_guard(): including it again (e.g. from a
# subdirectory) must re-set the variables in that scope; everything is idempotent.

# VCI_USE_PFUNIT is a top-level option (docs/BUILD.md); ON when this file is used on its own.
if(NOT DEFINED VCI_USE_PFUNIT)
  set(VCI_USE_PFUNIT ON)
endif()

# Debian's interpreter when present, for pfunit_lite's converter and for pFUnit's own
# preprocessor (PFUNIT_PARSER uses Python_EXECUTABLE): another python3 first on PATH
# (pyenv shims, virtual environments) may not run in every environment.
if(EXISTS /usr/bin/python3)
  if(NOT DEFINED Python3_EXECUTABLE)
    set(Python3_EXECUTABLE /usr/bin/python3)
  endif()
  if(NOT DEFINED Python_EXECUTABLE)
    set(Python_EXECUTABLE /usr/bin/python3)
  endif()
endif()

if(VCI_USE_PFUNIT AND NOT DEFINED PFUNIT_FOUND)
  find_package(PFUNIT QUIET)
endif()

set(VCI_PFUNIT_LITE TRUE)
if(VCI_USE_PFUNIT AND PFUNIT_FOUND)
  if(DEFINED PFUNIT_VERSION AND PFUNIT_VERSION VERSION_LESS 4)
    message(WARNING "pFUnit ${PFUNIT_VERSION} found but 4.x is required; using pfunit_lite")
  elseif(NOT COMMAND add_pfunit_ctest)
    message(WARNING "pFUnit found but add_pfunit_ctest() is missing; using pfunit_lite")
  else()
    set(VCI_PFUNIT_LITE FALSE)
  endif()
endif()

# Captured now: inside the function CMAKE_CURRENT_LIST_DIR is the caller's.
set(_VCI_PFUNIT_LITE_DIR "${CMAKE_CURRENT_LIST_DIR}/pfunit_lite")

# Both backends compile a suite with gfortran's free-form limit of 132 columns, a longer line
# being an error (the compiler's defaults, restated so that a -ffree-line-length-none in
# CMAKE_Fortran_FLAGS cannot hide a line that a default pFUnit build would reject).
set(VCI_PF_SUITE_OPTIONS
  $<$<Fortran_COMPILER_ID:GNU>:-ffree-line-length-132 -Werror=line-truncation>)

get_property(_vci_testing_reported GLOBAL PROPERTY _VCI_TESTING_REPORTED)
if(NOT _vci_testing_reported)
  set_property(GLOBAL PROPERTY _VCI_TESTING_REPORTED TRUE)
  if(VCI_PFUNIT_LITE)
    message(STATUS "vci tests: pFUnit 4 not used; using the pfunit_lite fallback")
  else()
    message(STATUS "vci tests: using pFUnit ${PFUNIT_VERSION}")
  endif()
endif()

# The fallback runtime (`use funit`), built once and shared by all suites.
function(_vci_add_funit_lite_library)
  if(TARGET vci_funit_lite)
    return()
  endif()
  set(mod_dir "${CMAKE_BINARY_DIR}/vci_funit_lite/mod")
  add_library(vci_funit_lite STATIC "${_VCI_PFUNIT_LITE_DIR}/funit.f90")
  set_target_properties(vci_funit_lite PROPERTIES Fortran_MODULE_DIRECTORY "${mod_dir}")
  target_include_directories(vci_funit_lite PUBLIC "$<BUILD_INTERFACE:${mod_dir}>")
  # The NaN-never-passes rule relies on IEEE comparisons; keep them even if
  # the project adds -ffast-math to its flags.
  target_compile_options(vci_funit_lite PRIVATE
    $<$<Fortran_COMPILER_ID:GNU>:-fno-finite-math-only>)
endfunction()

function(vci_add_pf_suite)
  cmake_parse_arguments(PARSE_ARGV 0 arg "WILL_FAIL" "NAME"
    "SOURCES;LINK;LABELS;EXTRA_SOURCES")
  if(arg_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR "vci_add_pf_suite: unknown arguments: ${arg_UNPARSED_ARGUMENTS}")
  endif()
  if(NOT arg_NAME OR NOT arg_SOURCES)
    message(FATAL_ERROR "vci_add_pf_suite: NAME and SOURCES are required")
  endif()
  set(name "${arg_NAME}")

  if(NOT VCI_PFUNIT_LITE)
    # Relative SOURCES are passed unchanged: add_pfunit_ctest resolves them
    # against CMAKE_CURRENT_SOURCE_DIR itself.
    add_pfunit_ctest(${name}
      TEST_SOURCES ${arg_SOURCES}
      OTHER_SOURCES ${arg_EXTRA_SOURCES}
      LINK_LIBRARIES ${arg_LINK})
  else()
    # the converter needs only Python's standard library
    find_package(Python3 COMPONENTS Interpreter REQUIRED)
    _vci_add_funit_lite_library()
    set(converter "${_VCI_PFUNIT_LITE_DIR}/pf2f90.py")
    set(gen_dir "${CMAKE_CURRENT_BINARY_DIR}/${name}.pf2f90")

    set(pf_files "")
    set(generated "")
    foreach(src IN LISTS arg_SOURCES)
      get_filename_component(pf "${src}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_SOURCE_DIR}")
      get_filename_component(stem "${src}" NAME_WE)
      set(out "${gen_dir}/${stem}.F90")
      add_custom_command(OUTPUT "${out}"
        COMMAND "${Python3_EXECUTABLE}" "${converter}" "${pf}" -o "${out}"
        DEPENDS "${pf}" "${converter}"
        COMMENT "pf2f90: ${src}"
        VERBATIM)
      list(APPEND pf_files "${pf}")
      list(APPEND generated "${out}")
    endforeach()

    set(driver "${gen_dir}/${name}_driver.F90")
    add_custom_command(OUTPUT "${driver}"
      COMMAND "${Python3_EXECUTABLE}" "${converter}" ${pf_files} --driver "${driver}"
      DEPENDS ${pf_files} "${converter}"
      COMMENT "pf2f90: driver for ${name}"
      VERBATIM)

    add_executable(${name} ${generated} "${driver}" ${arg_EXTRA_SOURCES})
    # Own module directory per suite: test modules of different suites may
    # share names without clobbering each other's .mod files.
    set_target_properties(${name} PROPERTIES
      Fortran_MODULE_DIRECTORY "${CMAKE_CURRENT_BINARY_DIR}/mod/${name}")
    # Like pFUnit: lets .pf files #include files next to them.
    target_include_directories(${name} PRIVATE "${CMAKE_CURRENT_SOURCE_DIR}")
    target_link_libraries(${name} PRIVATE vci_funit_lite ${arg_LINK})
    add_test(NAME ${name} COMMAND ${name})
  endif()
  target_compile_options(${name} PRIVATE ${VCI_PF_SUITE_OPTIONS})

  if(arg_LABELS)
    set_tests_properties(${name} PROPERTIES LABELS "${arg_LABELS}")
  endif()
  if(arg_WILL_FAIL)
    set_tests_properties(${name} PROPERTIES WILL_FAIL TRUE)
  endif()
endfunction()
