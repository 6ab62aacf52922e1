# The freeflex program, linked with Ipopt's static archives (FREEFLEX_STATIC_IPOPT), must
# not load Ipopt or its solvers as shared libraries: a symbol the archives failed to provide
# would otherwise have been taken silently from them. Run by CTest (static_ipopt_linkage).
execute_process(COMMAND ${READELF} -d ${PROGRAM} OUTPUT_VARIABLE dynamic RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "readelf -d ${PROGRAM} failed")
endif()
string(REGEX MATCHALL "Shared library: \\[[^]]*\\]" needed "${dynamic}")
message(STATUS "${PROGRAM} needs: ${needed}")
foreach(lib ipopt dmumps mumps_common lapack blas gfortran scotch)
  if(dynamic MATCHES "Shared library: \\[lib${lib}")
    message(FATAL_ERROR "${PROGRAM} loads lib${lib} as a shared library although it was linked with the static archives")
  endif()
endforeach()
