# SUNDIALS CVODES for freeflex, as the target SUNDIALS::cvodes.
#
# FREEFLEX_SUNDIALS=bundled (default): Debian's own source package of SUNDIALS, fetched by
#   scripts/install_deps.sh into third_party/sundials-src (`apt-get source sundials`), is
#   built here with optimization as a static library (ExternalProject; CVODES with its serial
#   vector, dense/band/sparse matrices and linear solvers, SPGMR and the other Krylov solvers,
#   and the Newton and fixed-point nonlinear solvers: about 45 C files, 10-20 s on 2 cores)
#   and installed into <build>/sundials. Debian's binary packages libsundials_* are compiled
#   without optimization (their debian/rules sets CMAKE_C_FLAGS to -fcommon alone, which
#   replaces the -O2 of dpkg's CFLAGS).
# FREEFLEX_SUNDIALS=system: the installed libsundials-dev (find_package(SUNDIALS)).
#
# Both give the same results to the bit: the bundled build's flags (FREEFLEX_SUNDIALS_C_FLAGS)
# are -O2 with floating-point contraction off, and no -march, so every operation rounds as
# in Debian's -O0 code. The bundled headers come first on the include path (-isystem
# <build>/sundials/include, before /usr/include); freeflex_check_sundials_headers() makes
# the library fail to compile if Debian's headers were picked up instead.

# Makes `target` (the freeflex library) fail to compile when its SUNDIALS headers are not the
# bundled build's: Debian's sundials_config.h declares CVODE, ARKODE and MPI (SUNDIALS_MPI_ENABLED
# 1), the bundled one CVODES alone. Does nothing with FREEFLEX_SUNDIALS=system.
function(freeflex_check_sundials_headers target)
  if(NOT FREEFLEX_SUNDIALS STREQUAL "bundled")
    return()
  endif()
  set(check "${CMAKE_BINARY_DIR}/freeflex_sundials_header_check.cpp")
  file(WRITE "${check}.in"
    "// Written by cmake/FreeflexSundials.cmake (FREEFLEX_SUNDIALS=bundled).\n"
    "#include <sundials/sundials_config.h>\n"
    "#if defined(SUNDIALS_CVODE) || defined(SUNDIALS_ARKODE) || SUNDIALS_MPI_ENABLED || !defined(SUNDIALS_CVODES)\n"
    "#error \"freeflex: the SUNDIALS headers are not the bundled build's (check the include order)\"\n"
    "#endif\n")
  configure_file("${check}.in" "${check}" COPYONLY)  # rewritten only when it changes
  target_sources(${target} PRIVATE "${check}")
endfunction()

set(FREEFLEX_SUNDIALS bundled CACHE STRING
  "SUNDIALS used: bundled (Debian's source package built with -O2, default) or system (the installed libsundials, -O0)")
set_property(CACHE FREEFLEX_SUNDIALS PROPERTY STRINGS bundled system)

if(FREEFLEX_SUNDIALS STREQUAL "system")
  find_package(SUNDIALS 6 REQUIRED COMPONENTS cvodes)
  message(STATUS "freeflex: SUNDIALS ${SUNDIALS_VERSION} of the system (FREEFLEX_SUNDIALS=system)")
  return()
elseif(NOT FREEFLEX_SUNDIALS STREQUAL "bundled")
  message(FATAL_ERROR "FREEFLEX_SUNDIALS is '${FREEFLEX_SUNDIALS}'; allowed: bundled, system")
endif()

set(FREEFLEX_SUNDIALS_SOURCE_DIR "${PROJECT_SOURCE_DIR}/third_party/sundials-src" CACHE PATH
  "Source of SUNDIALS for FREEFLEX_SUNDIALS=bundled (scripts/install_deps.sh fetches it)")
set(FREEFLEX_SUNDIALS_C_FLAGS "-O2 -ffp-contract=off" CACHE STRING
  "C flags of the bundled SUNDIALS (keep floating-point results bit-identical to Debian's: no -march, -ffast-math or contraction)")

set(_ff_sundials_stamp "${FREEFLEX_SUNDIALS_SOURCE_DIR}/.freeflex-source")
if(NOT EXISTS "${FREEFLEX_SUNDIALS_SOURCE_DIR}/CMakeLists.txt" OR NOT EXISTS "${_ff_sundials_stamp}")
  message(FATAL_ERROR
    "freeflex: no SUNDIALS source in ${FREEFLEX_SUNDIALS_SOURCE_DIR}.\n"
    "Run scripts/install_deps.sh (as root: it adds deb-src entries and runs apt-get source sundials), "
    "point FREEFLEX_SUNDIALS_SOURCE_DIR at an unpacked SUNDIALS 6 source, "
    "or configure with -DFREEFLEX_SUNDIALS=system to use the installed libsundials (compiled without optimization).")
endif()
file(STRINGS "${FREEFLEX_SUNDIALS_SOURCE_DIR}/CMakeLists.txt" _ff_sundials_major
  REGEX "^set\\(PACKAGE_VERSION_MAJOR \"[0-9]+\"\\)")
string(REGEX REPLACE ".*\"([0-9]+)\".*" "\\1" _ff_sundials_major "${_ff_sundials_major}")
if(NOT _ff_sundials_major STREQUAL "6")
  message(FATAL_ERROR "freeflex: ${FREEFLEX_SUNDIALS_SOURCE_DIR} is SUNDIALS '${_ff_sundials_major}', freeflex needs 6.x")
endif()
file(STRINGS "${_ff_sundials_stamp}" _ff_sundials_package LIMIT_COUNT 1)

include(ExternalProject)
set(_ff_sundials_prefix "${CMAKE_BINARY_DIR}/sundials")
set(_ff_sundials_lib
  "${_ff_sundials_prefix}/lib/${CMAKE_STATIC_LIBRARY_PREFIX}sundials_cvodes${CMAKE_STATIC_LIBRARY_SUFFIX}")
set(_ff_sundials_launcher "${CMAKE_C_COMPILER_LAUNCHER}")
if(NOT _ff_sundials_launcher)
  set(_ff_sundials_launcher "${CMAKE_CXX_COMPILER_LAUNCHER}")  # e.g. ccache, given for C++ only
endif()
ExternalProject_Add(freeflex_sundials
  SOURCE_DIR "${FREEFLEX_SUNDIALS_SOURCE_DIR}"
  PREFIX "${_ff_sundials_prefix}/ep"
  BINARY_DIR "${_ff_sundials_prefix}/build"
  INSTALL_DIR "${_ff_sundials_prefix}"
  CMAKE_ARGS
    -DCMAKE_C_COMPILER=${CMAKE_C_COMPILER}
    "-DCMAKE_C_COMPILER_LAUNCHER=${_ff_sundials_launcher}"
    -DCMAKE_BUILD_TYPE=Release
    "-DCMAKE_C_FLAGS="                                    # not the environment's CFLAGS
    "-DCMAKE_C_FLAGS_RELEASE=${FREEFLEX_SUNDIALS_C_FLAGS} -DNDEBUG"
    -DCMAKE_POSITION_INDEPENDENT_CODE=ON                # linkable into a shared freeflex too
    -DCMAKE_INSTALL_PREFIX=<INSTALL_DIR>
    -DCMAKE_INSTALL_LIBDIR=lib
    -DCMAKE_INSTALL_INCLUDEDIR=include
    -DBUILD_SHARED_LIBS=OFF -DBUILD_STATIC_LIBS=ON
    -DBUILD_CVODES=ON -DBUILD_CVODE=OFF -DBUILD_ARKODE=OFF -DBUILD_IDA=OFF -DBUILD_IDAS=OFF -DBUILD_KINSOL=OFF
    -DBUILD_NVECTOR_MANYVECTOR=OFF
    -DSUNDIALS_PRECISION=DOUBLE -DSUNDIALS_INDEX_SIZE=64  # as Debian's package
    -DENABLE_MPI=OFF -DENABLE_OPENMP=OFF -DENABLE_PTHREAD=OFF -DENABLE_LAPACK=OFF -DENABLE_KLU=OFF
    -DENABLE_HYPRE=OFF -DENABLE_PETSC=OFF -DBUILD_FORTRAN_MODULE_INTERFACE=OFF
    -DEXAMPLES_ENABLE_C=OFF -DEXAMPLES_ENABLE_CXX=OFF -DEXAMPLES_INSTALL=OFF
  BUILD_BYPRODUCTS "${_ff_sundials_lib}"
  LOG_CONFIGURE ON LOG_BUILD ON LOG_INSTALL ON LOG_OUTPUT_ON_FAILURE ON)
# a newly fetched source (its stamp file) configures and builds again
ExternalProject_Add_StepDependencies(freeflex_sundials configure "${_ff_sundials_stamp}")

file(MAKE_DIRECTORY "${_ff_sundials_prefix}/include")  # must exist when the target is defined
add_library(SUNDIALS::cvodes STATIC IMPORTED GLOBAL)
set_target_properties(SUNDIALS::cvodes PROPERTIES
  IMPORTED_LOCATION "${_ff_sundials_lib}"
  INTERFACE_INCLUDE_DIRECTORIES "${_ff_sundials_prefix}/include"
  INTERFACE_LINK_LIBRARIES m)
add_dependencies(SUNDIALS::cvodes freeflex_sundials)
set(FREEFLEX_SUNDIALS_LIBRARY "${_ff_sundials_lib}")
message(STATUS "freeflex: SUNDIALS ${_ff_sundials_package} from ${FREEFLEX_SUNDIALS_SOURCE_DIR}, "
               "built with ${FREEFLEX_SUNDIALS_C_FLAGS} (FREEFLEX_SUNDIALS=bundled)")
